#pragma once

#include <chrono>
#include <mutex>
#include <string>
#include <vector>

#include "absl/status/status.h"

namespace tetrefine::hardening {

// Outcomes of many calls from many threads: counts by status code, wrong results, latencies.
class CallStats {
 public:
  void Add(const absl::Status& status, bool correct, std::chrono::duration<double> latency);

  int calls() const;
  int count(absl::StatusCode code) const;
  int wrong() const;
  // Latency quantile q in [0, 1] over calls with `code`, seconds (0 without such calls).
  double Quantile(absl::StatusCode code, double q) const;
  // The first few error messages seen, for failure output.
  std::string ErrorSamples() const;

 private:
  mutable std::mutex mu_;
  std::vector<std::pair<absl::StatusCode, double>> latencies_;
  int wrong_ = 0;
  std::vector<std::string> errors_;
};

}  // namespace tetrefine::hardening
