#pragma once

#include <array>
#include <cstdint>

namespace tetrefine::reproduce {

// The paper's Tables 5 and 6 (INT, FNT, NTwE, max. error, av. error for four iterations) and
// Table 7 (mean quality), for the side-by-side comparison in the report. Values as printed.
struct PaperIteration {
  int64_t initial_tets, final_tets, tets_with_error;
  double max_error, mean_error;
};
struct PaperCase {
  const char* name;
  double epsilon;
  std::array<PaperIteration, 4> iterations;
  double initial_quality, final_quality;
};

inline constexpr std::array<PaperCase, 6> kPaperCases = {{
    {"heart1",
     0.10,
     {{{1009, 3176, 728, 0.471722, 0.179860},
       {3176, 4496, 723, 0.259945, 0.072018},
       {4496, 4554, 44, 0.183811, 0.049100},
       {4554, 4566, 10, 0.138826, 0.048729}}},
     0.565231,
     0.578719},
    {"heart2",
     0.10,
     {{{988, 3263, 744, 0.530826, 0.199676},
       {3263, 4043, 519, 0.257719, 0.071939},
       {4043, 4116, 53, 0.235371, 0.061403},
       {4116, 4162, 30, 0.184703, 0.060667}}},
     0.499718,
     0.508499},
    {"liver",
     0.10,
     {{{10955, 20482, 3648, 0.540841, 0.107953},
       {20482, 25552, 3333, 0.443069, 0.061281},
       {25552, 26613, 813, 0.239975, 0.050338},
       {26613, 26836, 171, 0.166551, 0.048441}}},
     0.333292,
     0.313060},
    {"heart1",
     0.05,
     {{{1009, 4040, 905, 0.471772, 0.179860},
       {4040, 8592, 1888, 0.322032, 0.060891},
       {8592, 9757, 725, 0.156437, 0.028232},
       {9757, 10047, 180, 0.138826, 0.025605}}},
     0.565231,
     0.574900},
    {"heart2",
     0.05,
     {{{988, 4342, 932, 0.530826, 0.199676},
       {4342, 10391, 2482, 0.257719, 0.062552},
       {10391, 11502, 829, 0.180630, 0.032707},
       {11502, 12033, 331, 0.154164, 0.030557}}},
     0.499718,
     0.507415},
    {"liver",
     0.05,
     {{{10955, 31780, 7421, 0.540841, 0.107953},
       {31780, 46206, 8629, 0.497772, 0.045310},
       {46206, 53060, 4519, 0.210582, 0.032588},
       {53060, 56605, 2382, 0.168926, 0.029993}}},
     0.333292,
     0.309224},
}};

// Section 5.1: share of tets whose lattice maximum lies at (or, for coarse meshes, near) an
// edge midpoint.
inline constexpr double kPaperVoxelShare = 0.93;
inline constexpr double kPaperCoarseShare0001 = 0.73;
inline constexpr double kPaperCoarseShare005 = 0.85;

}  // namespace tetrefine::reproduce
