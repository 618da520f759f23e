#include "client/cli/progress.h"

#include <cstdio>
#include <utility>

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
  std::lock_guard<std::mutex> lock(mu_);
  AbandonLocked();
  // stderr is unbuffered: the start of the line shows while the phase runs.
  std::fprintf(stderr, "tetrefine: %s ... ", what.c_str());
  open_ = true;
  start_ = std::chrono::steady_clock::now();
}

void Progress::End(const std::string& detail) {
  if (quiet_) return;
  std::lock_guard<std::mutex> lock(mu_);
  if (!open_) return;
  std::fprintf(stderr, "%s, %s\n", detail.c_str(), FormatSeconds(SecondsSince(start_)).c_str());
  open_ = false;
}

void Progress::Abandon() {
  if (quiet_) return;
  std::lock_guard<std::mutex> lock(mu_);
  AbandonLocked();
}

void Progress::AbandonLocked() {
  if (!open_) return;
  std::fputs("failed\n", stderr);
  open_ = false;
}

void Progress::Line(const std::string& text) {
  if (quiet_) return;
  std::lock_guard<std::mutex> lock(mu_);
  AbandonLocked();
  std::fprintf(stderr, "tetrefine: %s\n", text.c_str());
}

bool Progress::LineIfIdle(const std::string& text) {
  if (quiet_) return false;
  std::lock_guard<std::mutex> lock(mu_);
  if (open_) return false;
  std::fprintf(stderr, "tetrefine: %s\n", text.c_str());
  return true;
}

SilenceWatch::SilenceWatch(Progress& progress, std::function<std::string(double)> describe)
    : progress_(progress), describe_(std::move(describe)), last_(std::chrono::steady_clock::now()) {
  if (!progress_.quiet()) {
    thread_ = std::jthread([this](const std::stop_token& stop) { Watch(stop); });
  }
}

SilenceWatch::~SilenceWatch() {
  if (thread_.joinable()) {
    thread_.request_stop();
    thread_.join();
  }
}

void SilenceWatch::Touch(bool armed) {
  std::lock_guard<std::mutex> lock(mu_);
  armed_ = armed;
  last_ = std::chrono::steady_clock::now();
  next_report_seconds_ = 2.0;
}

void SilenceWatch::Watch(const std::stop_token& stop) {
  while (!stop.stop_requested()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    std::lock_guard<std::mutex> lock(mu_);
    const double silent = SecondsSince(last_);
    if (!armed_ || silent < next_report_seconds_) continue;
    // Printed under the lock, so that a Touch cannot slip between the check and the line.
    progress_.LineIfIdle(describe_(silent));
    next_report_seconds_ *= 2.0;
  }
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
