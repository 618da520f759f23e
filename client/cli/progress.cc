#include "client/cli/progress.h"

#include <cstdio>

#include "absl/strings/str_format.h"

namespace tetrefine::cli {
namespace {

// `value` with at most 3 significant digits, then `suffix`: "1.23 M", "12.3 M", "123 M".
std::string Scaled(double value, const char* suffix) {
  if (value < 10.0) return absl::StrFormat("%.2f %s", value, suffix);
  if (value < 100.0) return absl::StrFormat("%.1f %s", value, suffix);
  return absl::StrFormat("%.0f %s", value, suffix);
}

}  // namespace

void Progress::Begin(const std::string& what) {
  if (quiet_) return;
  Abandon();
  // stderr is unbuffered: the start of the line shows while the phase runs.
  std::fprintf(stderr, "tetrefine: %s ... ", what.c_str());
  open_ = true;
  start_ = std::chrono::steady_clock::now();
}

void Progress::End(const std::string& detail) {
  if (quiet_ || !open_) return;
  std::fprintf(stderr, "%s, %s\n", detail.c_str(), FormatSeconds(SecondsSince(start_)).c_str());
  open_ = false;
}

void Progress::Abandon() {
  if (quiet_ || !open_) return;
  std::fputs("failed\n", stderr);
  open_ = false;
}

void Progress::Line(const std::string& text) {
  if (quiet_) return;
  Abandon();
  std::fprintf(stderr, "tetrefine: %s\n", text.c_str());
}

std::string FormatCount(int64_t n) {
  const double x = static_cast<double>(n);
  if (n < 0) return absl::StrFormat("%d", n);
  if (n < 10000) return absl::StrFormat("%d", n);
  if (n < 1000000) return Scaled(x / 1e3, "k");
  if (n < 1000000000) return Scaled(x / 1e6, "M");
  return Scaled(x / 1e9, "G");
}

std::string FormatBytes(int64_t bytes) {
  const double x = static_cast<double>(bytes);
  if (bytes < 1000) return absl::StrFormat("%d B", bytes);
  if (bytes < 1000000) return Scaled(x / 1e3, "kB");
  if (bytes < 1000000000) return Scaled(x / 1e6, "MB");
  return Scaled(x / 1e9, "GB");
}

std::string FormatSeconds(double seconds) {
  return seconds < 10.0 ? absl::StrFormat("%.2f s", seconds) : absl::StrFormat("%.1f s", seconds);
}

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace tetrefine::cli
