#include "core/configuration.h"

namespace tetrefine {

std::string_view ConfigurationName(Configuration c) {
  static constexpr std::string_view kNames[kNumConfigurations] = {
      "0", "1", "2a", "2b", "3a", "3b", "3c", "4a", "4b", "5", "6"};
  return kNames[static_cast<int>(c)];
}

int ConfigurationTetCount(Configuration c, bool steiner) {
  static constexpr int kCounts[kNumConfigurations] = {1, 2, 3, 4, 4, 4, 5, 6, 6, 7, 8};
  if (steiner && c == Configuration::k3b) return 9;
  if (steiner && c == Configuration::k4b) return 11;
  return kCounts[static_cast<int>(c)];
}

}  // namespace tetrefine
