// libFuzzer target: the .pvti index parser on arbitrary text (the piece files are not read: the
// .vti reader, which assembles them, has its own target).

#include "absl/strings/string_view.h"
#include "client/io/vti_reader.h"
#include "fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const absl::string_view text(reinterpret_cast<const char*>(data), size);
  const auto sources = tetrefine::io::ParsePvtiIndex(text, "dir/input.pvti");
  if (!sources.ok()) {
    TETREFINE_FUZZ_CHECK(!sources.status().message().empty(), "an error without a message");
    return 0;
  }
  TETREFINE_FUZZ_CHECK(!sources->empty(), "an index accepted with no pieces");
  for (const std::string& source : *sources) {
    TETREFINE_FUZZ_CHECK(!source.empty(), "an empty piece path");
  }
  return 0;
}
