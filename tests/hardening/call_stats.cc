#include "tests/hardening/call_stats.h"

#include <algorithm>
#include <cmath>

namespace tetrefine::hardening {

void CallStats::Add(const absl::Status& status, bool correct,
                    std::chrono::duration<double> latency) {
  std::lock_guard<std::mutex> lock(mu_);
  latencies_.emplace_back(status.code(), latency.count());
  if (!correct) ++wrong_;
  if (!status.ok() && errors_.size() < 5) errors_.push_back(status.ToString());
}

int CallStats::calls() const {
  std::lock_guard<std::mutex> lock(mu_);
  return static_cast<int>(latencies_.size());
}

int CallStats::count(absl::StatusCode code) const {
  std::lock_guard<std::mutex> lock(mu_);
  return static_cast<int>(std::count_if(latencies_.begin(), latencies_.end(),
                                        [code](const auto& l) { return l.first == code; }));
}

int CallStats::wrong() const {
  std::lock_guard<std::mutex> lock(mu_);
  return wrong_;
}

double CallStats::Quantile(absl::StatusCode code, double q) const {
  std::vector<double> values;
  {
    std::lock_guard<std::mutex> lock(mu_);
    for (const auto& [c, seconds] : latencies_) {
      if (c == code) values.push_back(seconds);
    }
  }
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  // Nearest rank: the smallest value with at least a fraction q of the values at or below it.
  const double rank = std::ceil(q * static_cast<double>(values.size()));
  const size_t index = std::clamp<size_t>(static_cast<size_t>(rank), 1, values.size()) - 1;
  return values[index];
}

std::string CallStats::ErrorSamples() const {
  std::lock_guard<std::mutex> lock(mu_);
  std::string out;
  for (const std::string& e : errors_) out += "  " + e + "\n";
  return out;
}

}  // namespace tetrefine::hardening
