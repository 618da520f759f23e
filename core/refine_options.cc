#include "core/refine_options.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "absl/strings/str_cat.h"

namespace tetrefine {
namespace {

absl::Status Invalid(absl::string_view field, const auto& value, absl::string_view rule) {
  return absl::InvalidArgumentError(absl::StrCat("options.", field, ": ", rule, ", got ", value));
}

// Written so that NaN fails too.
bool FinitePositive(double x) { return x > 0.0 && std::isfinite(x); }
bool FiniteNonNegative(double x) { return x >= 0.0 && std::isfinite(x); }

}  // namespace

std::string_view RefineSchemeName(RefineScheme s) {
  switch (s) {
    case RefineScheme::kPaper:
      return "paper";
    case RefineScheme::kLongestEdge:
      return "longest-edge";
  }
  return "unknown";
}

bool ParseRefineScheme(std::string_view name, RefineScheme* out) {
  for (RefineScheme s : {RefineScheme::kPaper, RefineScheme::kLongestEdge}) {
    if (RefineSchemeName(s) == name) {
      *out = s;
      return true;
    }
  }
  return false;
}

absl::Status ValidateRefineOptions(const RefineOptions& o) {
  if (!FinitePositive(o.epsilon)) return Invalid("epsilon", o.epsilon, "must be finite and > 0");
  if (o.max_iterations < 0) return Invalid("max_iterations", o.max_iterations, "must be >= 0");
  if (o.max_tets < 1 || o.max_tets > kMaxTetsCeiling) {
    return Invalid("max_tets", o.max_tets, absl::StrCat("must be in [1, ", kMaxTetsCeiling, "]"));
  }
  if (o.norm_coeff.has_value() && !FinitePositive(*o.norm_coeff)) {
    return Invalid("norm_coeff", *o.norm_coeff, "must be finite and > 0");
  }
  if (o.threads < 0) return Invalid("threads", o.threads, "must be >= 0 (0: all cores)");
  if (o.min_edge_length.has_value() && !FiniteNonNegative(*o.min_edge_length)) {
    return Invalid("min_edge_length", *o.min_edge_length, "must be finite and >= 0");
  }
  if (o.min_quality.has_value() && !(*o.min_quality >= 0.0 && *o.min_quality < 1.0)) {
    return Invalid("min_quality", *o.min_quality, "must be in [0, 1)");
  }
  if (o.lattice_n < 0 || o.lattice_n > 64) {
    return Invalid("lattice_n", o.lattice_n, "must be in [0, 64]");
  }
  // Order 1 is the tet's four corners, where the discrepancy is 0 by construction (vertex values
  // are samples): it would certify 0 for any mesh. Orders 2 and 3 add points on the edges and
  // faces only (order 2: the edge midpoints, what the edge test already reads); order 4 is the
  // first with a point inside (1, 1, 1, 1) / 4. An outside review took a "Certified" of order 2
  // for a statement about the tets' insides.
  if (o.certify && o.lattice_n < 4) {
    return Invalid("lattice_n", o.lattice_n,
                   "certify needs a lattice with points inside the tets (lattice_n >= 4; orders "
                   "1-3 have points on the corners, edges and faces only)");
  }
  if (o.scheme != RefineScheme::kPaper && o.scheme != RefineScheme::kLongestEdge) {
    return Invalid("scheme", static_cast<int>(o.scheme), "not a scheme");
  }
  if (o.quality_reference.has_value() &&
      !(*o.quality_reference > 0.0 && *o.quality_reference <= 1.0)) {
    return Invalid("quality_reference", *o.quality_reference, "must be in (0, 1]");
  }
  if (o.lattice_max_tets < 0) {
    return Invalid("lattice_max_tets", o.lattice_max_tets, "must be >= 0");
  }
  return absl::OkStatus();
}

absl::Status CheckNormCoeffForRange(double norm_coeff, const std::array<double, 2>& range) {
  if (!std::isnormal(norm_coeff) || norm_coeff < 0.0) {
    return absl::InvalidArgumentError(
        absl::StrCat("options.norm_coeff: must be a positive normal number (>= ",
                     std::numeric_limits<double>::min(), "), got ", norm_coeff));
  }
  const double ratio = (range[1] - range[0]) / norm_coeff;
  if (!(ratio <= kMaxRangeOverNorm)) {
    return absl::InvalidArgumentError(absl::StrCat(
        "options.norm_coeff: ", norm_coeff, " is too small for the volume's value range [",
        range[0], ", ", range[1], "]: errors up to ", ratio,
        " would overflow the statistics; it must be at least range / ", kMaxRangeOverNorm));
  }
  return absl::OkStatus();
}

namespace {
// x > 0 rounded up to three significant digits (a threshold to quote: never below it).
double RoundedUp(double x) {
  const double unit = std::pow(10.0, std::floor(std::log10(x)) - 2.0);
  return std::ceil(x / unit * (1.0 + 1e-12)) * unit;
}
}  // namespace

absl::Status CheckValuePrecision(double norm_coeff, const std::array<double, 2>& range,
                                 double epsilon, bool norm_given) {
  constexpr double kSmallestNorm = 1e-290;
  if (norm_coeff < kSmallestNorm) {
    return absl::InvalidArgumentError(absl::StrCat(
        "volume: the normalisation ", norm_coeff, " (the value range [", range[0], ", ", range[1],
        "] unless options.norm_coeff is given) is below ", kSmallestNorm,
        ": float64 cannot resolve errors that small; scale the volume's values up"));
  }
  const double magnitude = std::max(std::abs(range[0]), std::abs(range[1]));
  const double noise = 16.0 * std::numeric_limits<double>::epsilon() * magnitude / norm_coeff;
  if (!(noise <= 0.01 * epsilon) && norm_given) {
    // A norm_coeff of 1e-12 for a volume that spans 13 was blamed on the volume, with remedies
    // for the volume (an outside review of the service, 2026-11-28). The smallest that passes:
    // noise = 16 eps M / norm <= epsilon / 100.
    const double smallest = 1600.0 * std::numeric_limits<double>::epsilon() * magnitude / epsilon;
    return absl::InvalidArgumentError(absl::StrCat(
        "options.norm_coeff: ", norm_coeff, " is too small for this volume, whose values reach ",
        magnitude, ": float64 rounding of the interpolation alone is about ", noise,
        " of it, above a hundredth of epsilon ", epsilon,
        ", so the errors would be rounding, not the data; use a norm_coeff of at least ",
        RoundedUp(smallest), ", or none for the volume's value range (", range[1] - range[0], ")"));
  }
  // What the rounding would be with the minimum subtracted: the values then reach the range.
  const double offset_noise =
      16.0 * std::numeric_limits<double>::epsilon() * (range[1] - range[0]) / norm_coeff;
  // The CLI checks its --norm-coeff here too (norm_given false): that one is not epsilon's fault.
  const bool norm_is_range = norm_coeff == range[1] - range[0];
  if (!(noise <= 0.01 * epsilon) && !(offset_noise <= 0.01 * epsilon) && norm_is_range) {
    // No offset helps: epsilon itself is below what float64 resolves (1e-300 on an int16 volume
    // was blamed on the volume, with an offset as the remedy: a service sweep, 2026-11-28).
    return absl::InvalidArgumentError(absl::StrCat(
        "options.epsilon: ", epsilon,
        " is below what float64 resolves on this volume: rounding of the interpolation alone is "
        "about ",
        noise, " of the normalisation ", norm_coeff, " (values reach ", magnitude,
        "), above a hundredth of epsilon, so the errors would be rounding, not the data; use an "
        "epsilon of at least ",
        RoundedUp(100.0 * noise)));
  }
  if (!(noise <= 0.01 * epsilon)) {
    // The remedies end with the smallest epsilon that would pass: a tiny epsilon on an ordinary
    // volume was blamed on the volume alone (an outside review, 2026-11-28). The CLI's
    // --norm-coeff message keeps the text before "; subtract an offset" (cli/command_support).
    // A constant volume has no range: its normalisation is 1 (RefineInArena), said as such.
    const std::string spread =
        range[1] > range[0]
            ? absl::StrCat(" but vary over only ", norm_coeff, " (the normalisation)")
            : absl::StrCat(" and are all equal (a constant volume, normalised by ", norm_coeff,
                           ")");
    return absl::InvalidArgumentError(absl::StrCat(
        "volume: values reach ", magnitude, spread,
        ": float64 rounding of the interpolation alone is about ", noise,
        " of it, above a hundredth of epsilon ", epsilon,
        ", so the errors would be rounding, not the data; subtract an offset (e.g. the minimum, ",
        range[0], ") from the volume first, or use an epsilon of at least ",
        RoundedUp(100.0 * noise)));
  }
  return absl::OkStatus();
}

double QualityFloor(const std::optional<double>& min_quality, double input_worst) {
  return min_quality.value_or(std::min(kDefaultMinQuality, 0.5 * input_worst));
}

}  // namespace tetrefine
