#include "client/cli/convergence_stats.h"

#include <cmath>
#include <nlohmann/json.hpp>

#include "absl/strings/str_cat.h"
#include "client/io/file_bytes.h"

namespace tetrefine::cli {
namespace {

using Json = nlohmann::json;

absl::Status FieldError(const std::string& field, absl::string_view problem) {
  return absl::InvalidArgumentError(absl::StrCat(field, ": ", problem));
}

// A number (not null: the writer writes NaN and infinities as null).
absl::StatusOr<double> Number(const Json& object, const std::string& key,
                              const std::string& field) {
  auto it = object.find(key);
  if (it == object.end()) return FieldError(field, "missing");
  if (!it->is_number())
    return FieldError(field, absl::StrCat("expected a number, got ", it->dump()));
  return it->get<double>();
}

absl::StatusOr<int64_t> Count(const Json& object, const std::string& key,
                              const std::string& field) {
  auto it = object.find(key);
  if (it == object.end()) return FieldError(field, "missing");
  if (!it->is_number_integer() || it->get<int64_t>() < 0) {
    return FieldError(field, absl::StrCat("expected a whole number >= 0, got ", it->dump()));
  }
  return it->get<int64_t>();
}

// The string at `key`, "" when absent; an error when it is there but not a string.
absl::StatusOr<std::string> OptionalString(const Json& object, const std::string& key,
                                           const std::string& field) {
  auto it = object.find(key);
  if (it == object.end() || it->is_null()) return std::string();
  if (!it->is_string())
    return FieldError(field, absl::StrCat("expected a string, got ", it->dump()));
  return it->get<std::string>();
}

// OK when `key` is absent, null or a number >= 0; an error naming `field` for a negative one.
absl::Status CheckNonNegative(const Json& object, const std::string& key,
                              const std::string& field) {
  auto it = object.find(key);
  if (it == object.end() || !it->is_number() || it->get<double>() >= 0.0) {
    return absl::OkStatus();
  }
  return FieldError(field, absl::StrCat("must be >= 0, got ", it->get<double>()));
}

bool IsStopReason(const std::string& name) {
  for (const char* known : {"converged", "max_iterations", "tet_budget", "cancelled",
                            "quality_floor", "min_edge_length"}) {
    if (name == known) return true;
  }
  return false;
}

absl::StatusOr<ConvergenceRun> FromJson(const Json& root) {
  if (!root.is_object()) return absl::InvalidArgumentError("expected a JSON object at the top");
  ConvergenceRun run;
  auto options = root.find("options");
  if (options == root.end() || !options->is_object()) {
    return FieldError("options", "missing (not a tetrefine refine --stats-json file?)");
  }
  absl::StatusOr<double> epsilon = Number(*options, "epsilon", "options.epsilon");
  if (!epsilon.ok()) return epsilon.status();
  if (!(*epsilon > 0.0))
    return FieldError("options.epsilon", absl::StrCat("must be > 0, got ", *epsilon));
  run.epsilon = *epsilon;
  absl::StatusOr<std::string> scheme = OptionalString(*options, "scheme", "options.scheme");
  if (!scheme.ok()) return scheme.status();
  run.scheme = *scheme;
  if (auto certify = options->find("certify"); certify != options->end() && !certify->is_null()) {
    if (!certify->is_boolean()) {
      return FieldError("options.certify",
                        absl::StrCat("expected true or false, got ", certify->dump()));
    }
    run.certify = certify->get<bool>();
  }
  if (auto norm = options->find("norm_coeff"); norm != options->end() && !norm->is_null()) {
    if (!norm->is_number() || !(norm->get<double>() > 0.0)) {
      return FieldError("options.norm_coeff",
                        absl::StrCat("expected a number > 0 or null, got ", norm->dump()));
    }
    run.norm_coeff = norm->get<double>();
  }
  absl::StatusOr<std::string> stop = OptionalString(root, "stop_reason", "stop_reason");
  if (!stop.ok()) return stop.status();
  run.stop_reason = *stop;
  if (!run.stop_reason.empty() && !IsStopReason(run.stop_reason)) {
    return FieldError("stop_reason", absl::StrCat("\"", run.stop_reason,
                                                  "\" is not one refine writes (converged, "
                                                  "max_iterations, tet_budget, cancelled, "
                                                  "quality_floor, min_edge_length)"));
  }
  if (absl::Status s = CheckNonNegative(root, "final_mean_error", "final_mean_error"); !s.ok()) {
    return s;
  }
  if (absl::Status s = CheckNonNegative(root, "certified_max_error", "certified_max_error");
      !s.ok()) {
    return s;
  }
  if (auto certified = root.find("certified_max_error");
      certified != root.end() && certified->is_number()) {
    if (!run.certify) {
      return FieldError("certified_max_error", "set, but options.certify is not true");
    }
    run.certified = true;
  }
  // The run's own normalisation, when given, is the one the top level reports.
  if (auto top = root.find("norm_coeff"); run.norm_coeff.has_value() && top != root.end() &&
                                          top->is_number() &&
                                          top->get<double>() != *run.norm_coeff) {
    return FieldError("norm_coeff", absl::StrCat(top->get<double>(), " is not options.norm_coeff ",
                                                 *run.norm_coeff));
  }

  auto iterations = root.find("iterations");
  if (iterations == root.end()) return FieldError("iterations", "missing");
  if (!iterations->is_array()) return FieldError("iterations", "expected an array");
  // input.tets: the first point when no iteration ran, else what the first one starts from.
  auto input = root.find("input");
  const bool has_input = input != root.end() && input->is_object();
  std::optional<int64_t> input_tets;
  if (has_input && (iterations->empty() || input->contains("tets"))) {
    absl::StatusOr<int64_t> tets = Count(*input, "tets", "input.tets");
    if (!tets.ok()) return tets.status();
    input_tets = *tets;
  }
  if (iterations->empty()) {
    // A run that met epsilon (or its budget) before its first iteration: the input mesh is the
    // result, one point at iteration 0. A pipeline plotting every run must not fail on it.
    if (!has_input) {
      return FieldError("input", "missing: with no iteration, the plot needs input.tets");
    }
    run.tets.push_back(*input_tets);
  }
  for (size_t i = 0; i < iterations->size(); ++i) {
    const Json& it = (*iterations)[i];
    const std::string at = absl::StrCat("iterations[", i, "]");
    if (!it.is_object()) return FieldError(at, "expected an object");
    if (i == 0) {
      absl::StatusOr<int64_t> initial = Count(it, "initial_tets", at + ".initial_tets");
      if (!initial.ok()) return initial.status();
      if (input_tets.has_value() && *input_tets != *initial) {
        return FieldError(at + ".initial_tets",
                          absl::StrCat(*initial, " is not the input's ", *input_tets, " tets"));
      }
      run.tets.push_back(*initial);
    }
    if (absl::Status s = CheckNonNegative(it, "mean_error", at + ".mean_error"); !s.ok()) return s;
    // The checks below refuse what no run of refine writes (an outside review, 2026-11-28,
    // plotted an error of -1 as a silent gap and reversed iterations as "tets 29291 -> 5175").
    if (auto number = it.find("iteration"); number != it.end()) {
      if (!number->is_number_integer() || number->get<int64_t>() != static_cast<int64_t>(i) + 1) {
        return FieldError(
            at + ".iteration",
            absl::StrCat("expected ", i + 1, " (iterations in order), got ", number->dump()));
      }
    }
    if (i > 0 && it.contains("initial_tets")) {
      absl::StatusOr<int64_t> initial = Count(it, "initial_tets", at + ".initial_tets");
      if (!initial.ok()) return initial.status();
      if (*initial != run.tets.back()) {
        return FieldError(at + ".initial_tets",
                          absl::StrCat(*initial, " is not the ", run.tets.back(),
                                       " tets the iteration before ended with"));
      }
    }
    absl::StatusOr<double> error = Number(it, "max_error", at + ".max_error");
    if (!error.ok()) return error.status();
    if (!(*error >= 0.0)) {
      return FieldError(at + ".max_error", absl::StrCat("must be >= 0, got ", *error));
    }
    absl::StatusOr<int64_t> final_tets = Count(it, "final_tets", at + ".final_tets");
    if (!final_tets.ok()) return final_tets.status();
    run.max_error.push_back(*error);
    run.tets.push_back(*final_tets);
  }
  if (auto output = root.find("output_mesh");
      output != root.end() && output->is_object() && output->contains("tets")) {
    absl::StatusOr<int64_t> tets = Count(*output, "tets", "output_mesh.tets");
    if (!tets.ok()) return tets.status();
    if (*tets != run.tets.back() && run.stop_reason != "cancelled") {
      return FieldError("output_mesh.tets",
                        absl::StrCat(*tets, " is not the ", run.tets.back(), " tets ",
                                     iterations->empty() ? "of the input (no iteration ran)"
                                                         : "the last iteration ended with"));
    }
  }
  auto final_error = root.find("final_max_error");
  if (final_error != root.end() && final_error->is_number() && run.stop_reason != "cancelled") {
    if (!(final_error->get<double>() >= 0.0)) {
      return FieldError("final_max_error",
                        absl::StrCat("must be >= 0, got ", final_error->get<double>()));
    }
    // "converged" means no edge-midpoint error above epsilon: a file that says both was drawn
    // (with an axis up to 1e300: an outside review, 2026-11-28).
    if (run.stop_reason == "converged" && final_error->get<double>() > run.epsilon) {
      return FieldError("final_max_error",
                        absl::StrCat(final_error->get<double>(), " is above options.epsilon ",
                                     run.epsilon, ", but stop_reason is \"converged\""));
    }
    run.max_error.push_back(final_error->get<double>());
  }
  return run;
}

// "[json.exception.parse_error.101] parse error at ..." -> "parse error at ...".
std::string WithoutExceptionId(const std::string& what) {
  if (what.empty() || what[0] != '[') return what;
  const size_t end = what.find("] ");
  return end == std::string::npos ? what : what.substr(end + 2);
}

}  // namespace

absl::StatusOr<ConvergenceRun> ParseConvergenceRun(std::string_view json_text) {
  Json root;
  try {
    root = Json::parse(json_text);
  } catch (const Json::exception& e) {
    return absl::InvalidArgumentError(
        absl::StrCat("not valid JSON: ", WithoutExceptionId(e.what())));
  }
  return FromJson(root);
}

absl::StatusOr<ConvergenceRun> ReadConvergenceRun(const std::string& path) {
  absl::StatusOr<std::string> text = io::ReadFileBytes(path);
  if (!text.ok()) return text.status();
  absl::StatusOr<ConvergenceRun> run = ParseConvergenceRun(*text);
  if (!run.ok()) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": ", run.status().message()));
  }
  return run;
}

}  // namespace tetrefine::cli
