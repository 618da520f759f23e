#include "fuzz/fuzz_support.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

namespace tetrefine::fuzz {

void Fail(const char* file, int line, const std::string& what) {
  std::fprintf(stderr, "%s:%d: fuzz invariant failed: %s\n", file, line, what.c_str());
  std::fflush(stderr);
  std::abort();
}

std::string_view ByteSource::Bytes(size_t n) {
  if (n > size_ - offset_) n = size_ - offset_;
  const std::string_view out(reinterpret_cast<const char*>(data_ + offset_), n);
  offset_ += n;
  return out;
}

bool AnyKeyLineContains(std::string_view text, std::initializer_list<std::string_view> keys,
                        char c) {
  std::string lower(text);
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  for (std::string_view key : keys) {
    for (size_t at = lower.find(key); at != std::string::npos; at = lower.find(key, at + 1)) {
      const size_t end = lower.find('\n', at);
      if (lower.substr(at, end == std::string::npos ? end : end - at).find(c) !=
          std::string::npos) {
        return true;
      }
    }
  }
  return false;
}

std::string WritePrivateFile(std::string_view name, std::string_view bytes) {
  static const std::string* const dir = [] {
    const char* tmp = std::getenv("TMPDIR");
    std::string pattern =
        std::string(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") + "/tetrefine-fuzz-XXXXXX";
    if (mkdtemp(pattern.data()) == nullptr) Fail(__FILE__, __LINE__, "mkdtemp " + pattern);
    // Removed at exit so that a long fuzzing run leaves nothing behind.
    static std::string to_remove = pattern;
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(to_remove, ec);
    });
    return new std::string(pattern);
  }();
  const std::string path = *dir + "/" + std::string(name);
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) Fail(__FILE__, __LINE__, "cannot write " + path);
  if (!bytes.empty() && std::fwrite(bytes.data(), 1, bytes.size(), file) != bytes.size()) {
    Fail(__FILE__, __LINE__, "short write to " + path);
  }
  std::fclose(file);
  return path;
}

void CheckPieceSources(const absl::StatusOr<std::vector<std::string>>& sources) {
  if (!sources.ok()) {
    TETREFINE_FUZZ_CHECK(!sources.status().message().empty(), "an error without a message");
    return;
  }
  TETREFINE_FUZZ_CHECK(!sources->empty(), "an index accepted with no pieces");
  for (const std::string& source : *sources) {
    TETREFINE_FUZZ_CHECK(!source.empty(), "an empty piece path");
  }
}

}  // namespace tetrefine::fuzz
