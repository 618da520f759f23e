#include "client/cli/arg_parser.h"

#include <algorithm>
#include <charconv>
#include <cmath>

#include "absl/strings/str_cat.h"

namespace tetrefine::cli {
namespace {

std::string Normalize(std::string_view name) {
  std::string out(name);
  std::replace(out.begin(), out.end(), '_', '-');
  return out;
}

const FlagSpec* FindFlag(const CommandSpec& spec, const std::string& name) {
  for (const FlagSpec& flag : spec.flags) {
    if (flag.name == name) return &flag;
  }
  return nullptr;
}

std::string CommandName(const CommandSpec& spec) { return absl::StrCat("tetrefine ", spec.name); }

}  // namespace

std::optional<std::string> ParsedArgs::Get(std::string_view flag) const {
  auto it = values_.find(std::string(flag));
  if (it == values_.end()) return std::nullopt;
  return it->second.back();
}

std::vector<std::string> ParsedArgs::GetAll(std::string_view flag) const {
  auto it = values_.find(std::string(flag));
  if (it == values_.end()) return {};
  return it->second;
}

absl::StatusOr<ParsedArgs> ParseArgs(const CommandSpec& spec,
                                     const std::vector<std::string>& args) {
  ParsedArgs parsed;
  bool have_positional = false;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    if (arg == "-h" || arg == "--help" || arg == "-help") {
      parsed.help_ = true;
      continue;
    }
    if (arg.size() < 2 || arg.substr(0, 2) != "--") {
      if (arg.size() > 1 && arg[0] == '-') {
        return absl::InvalidArgumentError(absl::StrCat(
            "unknown flag ", arg, " for '", CommandName(spec), "' (flags start with --)"));
      }
      if (spec.positional.empty()) {
        return absl::InvalidArgumentError(
            absl::StrCat("unexpected argument '", arg, "' for '", CommandName(spec), "'"));
      }
      if (have_positional) {
        return absl::InvalidArgumentError(absl::StrCat("'", CommandName(spec), "' takes one ",
                                                       spec.positional, ", got a second: '", arg,
                                                       "'"));
      }
      parsed.positional_ = arg;
      have_positional = true;
      continue;
    }
    const size_t equals = arg.find('=');
    const std::string name =
        Normalize(arg.substr(2, equals == std::string::npos ? std::string::npos : equals - 2));
    const FlagSpec* flag = FindFlag(spec, name);
    if (flag == nullptr) {
      return absl::InvalidArgumentError(absl::StrCat("unknown flag --", name, " for '",
                                                     CommandName(spec), "' (see ",
                                                     CommandName(spec), " --help)"));
    }
    if (parsed.values_.count(name) > 0 && !flag->repeated) {
      return absl::InvalidArgumentError(absl::StrCat("--", name, " given twice"));
    }
    std::string value;
    if (flag->value_name.empty()) {
      if (equals != std::string::npos) {
        return absl::InvalidArgumentError(absl::StrCat("--", name, " takes no value"));
      }
    } else if (equals != std::string::npos) {
      value = arg.substr(equals + 1);
    } else {
      // A value may start with '-' (a negative number) but not with "--" (the next flag).
      if (i + 1 >= args.size() || args[i + 1].substr(0, 2) == "--") {
        return absl::InvalidArgumentError(
            absl::StrCat("--", name, ": missing value (", flag->value_name, ")"));
      }
      value = args[++i];
    }
    parsed.values_[name].push_back(std::move(value));
  }
  if (parsed.help_) return parsed;
  for (const FlagSpec& flag : spec.flags) {
    if (flag.required && parsed.values_.count(flag.name) == 0) {
      return absl::InvalidArgumentError(absl::StrCat("missing required flag --", flag.name, " ",
                                                     flag.value_name, " (see ", CommandName(spec),
                                                     " --help)"));
    }
  }
  if (!spec.positional.empty() && !have_positional) {
    return absl::InvalidArgumentError(
        absl::StrCat("missing ", spec.positional, " (usage: ", spec.usage, ")"));
  }
  return parsed;
}

std::string HelpText(const CommandSpec& spec) {
  std::string text = absl::StrCat(spec.summary, "\n\nUsage: ", spec.usage, "\n");
  if (!spec.description.empty()) absl::StrAppend(&text, "\n", spec.description, "\n");
  if (spec.flags.empty()) return text;
  absl::StrAppend(&text, "\nFlags:\n");
  size_t width = 0;
  std::vector<std::string> heads;
  for (const FlagSpec& flag : spec.flags) {
    std::string head = absl::StrCat("  --", flag.name);
    if (!flag.value_name.empty()) absl::StrAppend(&head, " ", flag.value_name);
    width = std::max(width, head.size());
    heads.push_back(std::move(head));
  }
  for (size_t i = 0; i < spec.flags.size(); ++i) {
    const FlagSpec& flag = spec.flags[i];
    absl::StrAppend(&text, heads[i], std::string(width + 2 - heads[i].size(), ' '), flag.help,
                    flag.required ? " (required)" : "", flag.repeated ? " (repeatable)" : "", "\n");
  }
  const std::string help_head = "  -h, --help";
  absl::StrAppend(&text, help_head,
                  std::string(width + 2 > help_head.size() ? width + 2 - help_head.size() : 2, ' '),
                  "this help\n");
  return text;
}

absl::StatusOr<double> ParseFiniteDouble(std::string_view flag, const std::string& text) {
  double value = 0.0;
  const char* begin = text.data();
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(begin, end, value);
  if (text.empty() || ec == std::errc::invalid_argument || ptr != end) {
    return absl::InvalidArgumentError(
        absl::StrCat("--", std::string(flag), ": expected a number, got '", text, "'"));
  }
  if (ec == std::errc::result_out_of_range || !std::isfinite(value)) {
    return absl::InvalidArgumentError(
        absl::StrCat("--", std::string(flag), ": expected a finite number, got '", text, "'"));
  }
  return value;
}

absl::StatusOr<int64_t> ParseInteger(std::string_view flag, const std::string& text, int64_t min,
                                     int64_t max) {
  int64_t value = 0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (text.empty() || ec == std::errc::invalid_argument || ptr != end) {
    return absl::InvalidArgumentError(
        absl::StrCat("--", std::string(flag), ": expected a whole number, got '", text, "'"));
  }
  if (ec == std::errc::result_out_of_range || value < min || value > max) {
    return absl::InvalidArgumentError(absl::StrCat("--", std::string(flag),
                                                   ": expected a whole number in [", min, ", ", max,
                                                   "], got '", text, "'"));
  }
  return value;
}

}  // namespace tetrefine::cli
