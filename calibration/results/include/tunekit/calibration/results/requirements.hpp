#pragma once
// CI thresholds: `--require EXPR` on every analysis command, e.g. `tau_s<0.6` or
// `x.freq_hz>=35`. An expression is PATH OP NUMBER with OP one of < <= > >= == !=.
// PATH names a number in the command's `results` by the last keys of its path
// (requirement_path_matches() is the rule), so `tau_s` finds
// `results.pooled.params.tau_s.value` (an object with a `value` stands for its value) and
// `x.freq_hz` finds `results.axes.x...freq_hz`. Among the matches a number outside any array
// wins over one inside an array, then the one with the fewest path segments, then a fitted
// parameter (a member of a `params` object); a tie between different numbers is an error
// listing the candidates. A fit's diagnostics (`diagnostics.n`, the number of observations)
// are matched only when the path says `diagnostics`: in `rheo`, `n` is the flow index. Full
// paths with indices (`axes.x.modes[1].freq_hz`) are accepted too.

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace tunekit::calibration {

struct Requirement {
  std::string expression;  ///< as written
  std::string path;        ///< as written (left-hand side)
  std::string op;
  double threshold = 0;
};

struct RequirementOutcome {
  Requirement requirement;
  std::string resolved_path;             ///< the full path in results that was compared ("axes.x.modes[0].freq_hz")
  nlohmann::json::json_pointer pointer;  ///< the same number's exact address (/axes/x/modes/0/freq_hz)
  double value = 0;
  bool met = false;
};

/// A path's segments as --require writes them: "axes.x.modes[1].freq_hz" ->
/// {"axes", "x", "modes", "[1]", "freq_hz"} (an array index keeps its brackets).
std::vector<std::string> split_requirement_path(const std::string& path);

/// The one rule by which a --require PATH names a number: `wanted` (PATH's segments) ends with
/// the number's last segment, and its other segments appear, in order, among the number's
/// earlier segments: a path suffix in which segments may be left out, so that "tau_s" names
/// pooled.params.tau_s and "x.freq_hz" names axes.x.modes[0].freq_hz. `number` is the number's
/// path with a final "value" dropped (pooled.params.tau_s for pooled.params.tau_s.value).
bool requirement_path_matches(const std::vector<std::string>& wanted, const std::vector<std::string>& number);

/// Parses "PATH OP NUMBER"; throws InputError (exit 2) when malformed.
Requirement parse_requirement(const std::string& expression);

/// Evaluates a requirement against a `results` object; throws InputError (exit 2) when the
/// path matches nothing or is ambiguous.
RequirementOutcome evaluate_requirement(const Requirement& r, const nlohmann::json& results);

}  // namespace tunekit::calibration
