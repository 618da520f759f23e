#pragma once

// A small per-subcommand flag parser. absl::flags is process-global, which would make every
// subcommand accept every other's flags; this one knows exactly one subcommand's flags, so it can
// say "unknown flag" and "missing --volume" precisely, and print a help that lists only them.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"

namespace tetrefine::cli {

struct FlagSpec {
  std::string name;        // written --name (an underscore is accepted for a dash)
  std::string value_name;  // shown in help ("FILE"); empty: a switch that takes no value
  std::string help;
  bool required = false;
  // May be given more than once (--stats-json A --stats-json B); ParsedArgs::GetAll has them all.
  bool repeated = false;
};

struct CommandSpec {
  std::string name;         // "refine"
  std::string summary;      // one line, for `tetrefine --help`
  std::string usage;        // "tetrefine refine --volume V ..."
  std::string description;  // free text after the usage line; may be empty
  std::vector<FlagSpec> flags;
  std::string positional;  // name of the one positional argument ("FILE"), or empty for none
};

class ParsedArgs {
 public:
  bool help() const { return help_; }
  bool Has(std::string_view flag) const { return values_.count(std::string(flag)) > 0; }
  // The value given for `flag`, or nullopt. Switches have the value "".
  std::optional<std::string> Get(std::string_view flag) const;
  // Every value given for `flag`, in command-line order (empty when not given). For a flag that is
  // not `repeated` this is at most one.
  std::vector<std::string> GetAll(std::string_view flag) const;
  // The positional argument, or "" when the command takes none.
  const std::string& positional() const { return positional_; }

 private:
  friend absl::StatusOr<ParsedArgs> ParseArgs(const CommandSpec&, const std::vector<std::string>&);
  bool help_ = false;
  std::map<std::string, std::vector<std::string>> values_;  // at least one value per flag given
  std::string positional_;
};

// Parses `args` (without the program and subcommand names): --flag VALUE, --flag=VALUE, switches,
// -h/--help. Errors are one line naming the flag: unknown, given twice (unless `repeated`),
// missing value, missing required flag (not checked when help is asked for).
absl::StatusOr<ParsedArgs> ParseArgs(const CommandSpec& spec, const std::vector<std::string>& args);

// The subcommand's help: usage, description and every flag with its help.
std::string HelpText(const CommandSpec& spec);

// Typed flag values. Errors name the flag and quote the text: "--epsilon: expected a number, got
// 'abc'".
absl::StatusOr<double> ParseFiniteDouble(std::string_view flag, const std::string& text);
absl::StatusOr<int64_t> ParseInteger(std::string_view flag, const std::string& text, int64_t min,
                                     int64_t max);

}  // namespace tetrefine::cli
