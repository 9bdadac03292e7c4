#include "tunekit/calibration/results/requirements.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <tuple>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"

namespace tunekit::calibration {
namespace {

struct RequirementLeaf {
  std::vector<std::string> segments;  // "modes[0]" is one segment "modes" followed by "[0]"; a final "value" dropped
  nlohmann::json::json_pointer pointer;
  std::string path;  // dotted, as shown to users
  double value;
};

// Every number in `j`, with its path.
void requirement_leaves(const nlohmann::json& j, std::vector<std::string>& segs, nlohmann::json::json_pointer& ptr,
                        std::vector<RequirementLeaf>& out) {
  if (j.is_number()) {
    std::string path;
    for (const auto& s : segs) path += (s.front() == '[' || path.empty()) ? s : "." + s;
    auto effective = segs;
    if (!effective.empty() && effective.back() == "value") effective.pop_back();
    out.push_back({effective, ptr, path, j.get<double>()});
    return;
  }
  if (j.is_object()) {
    for (const auto& [k, v] : j.items()) {
      segs.push_back(k);
      ptr /= k;
      requirement_leaves(v, segs, ptr, out);
      ptr.pop_back();
      segs.pop_back();
    }
  } else if (j.is_array()) {
    for (std::size_t i = 0; i < j.size(); ++i) {
      segs.push_back("[" + std::to_string(i) + "]");
      ptr /= i;
      requirement_leaves(j[i], segs, ptr, out);
      ptr.pop_back();
      segs.pop_back();
    }
  }
}

}  // namespace

std::vector<std::string> split_requirement_path(const std::string& p) {
  std::vector<std::string> segs;
  std::string cur;
  for (char c : p) {
    if (c == '.') {
      if (!cur.empty()) segs.push_back(cur);
      cur.clear();
    } else if (c == '[') {
      if (!cur.empty()) segs.push_back(cur);
      cur = "[";
    } else if (c == ']') {
      segs.push_back(cur + "]");
      cur.clear();
    } else {
      cur += c;
    }
  }
  if (!cur.empty()) segs.push_back(cur);
  return segs;
}

bool requirement_path_matches(const std::vector<std::string>& wanted, const std::vector<std::string>& number) {
  if (wanted.empty() || number.empty() || wanted.back() != number.back()) return false;
  std::size_t i = 0;
  for (const auto& h : number)
    if (i < wanted.size() && h == wanted[i]) ++i;
  return i == wanted.size();
}

Requirement parse_requirement(const std::string& expr) {
  static const char* ops[] = {"<=", ">=", "==", "!=", "<", ">"};
  for (const char* op : ops) {
    const auto pos = expr.find(op);
    if (pos == std::string::npos) continue;
    Requirement r;
    r.expression = expr;
    r.op = op;
    auto trim = [](std::string s) {
      s.erase(0, s.find_first_not_of(" \t"));
      s.erase(s.find_last_not_of(" \t") + 1);
      return s;
    };
    r.path = trim(expr.substr(0, pos));
    const std::string rhs = trim(expr.substr(pos + std::string(op).size()));
    const auto [ptr, ec] = std::from_chars(rhs.data(), rhs.data() + rhs.size(), r.threshold);
    if (r.path.empty() || rhs.empty() || ec != std::errc() || ptr != rhs.data() + rhs.size() ||
        !std::isfinite(r.threshold))
      throw InputError(fmt::format("--require '{}': expected PATH OP NUMBER, e.g. 'tau_s<0.6'", expr));
    return r;
  }
  throw InputError(fmt::format("--require '{}': no comparison (<, <=, >, >=, ==, !=)", expr));
}

RequirementOutcome evaluate_requirement(const Requirement& r, const nlohmann::json& results) {
  std::vector<RequirementLeaf> leaves;
  std::vector<std::string> segs;
  nlohmann::json::json_pointer ptr;
  requirement_leaves(results, segs, ptr, leaves);
  const auto want = split_requirement_path(r.path);
  // A fit's diagnostics (observation counts, RMS, ...) are matched only when the path names
  // them: a bare 'n' means the flow index n of a rheology fit, never the number of samples.
  const bool wants_diagnostics = std::find(want.begin(), want.end(), "diagnostics") != want.end();
  auto is_diagnostic = [](const RequirementLeaf& l) {
    return std::find(l.segments.begin(), l.segments.end(), "diagnostics") != l.segments.end();
  };
  std::vector<const RequirementLeaf*> found;
  std::vector<const RequirementLeaf*> diagnostics_only;
  for (const auto& l : leaves)
    if (requirement_path_matches(want, l.segments))
      (wants_diagnostics || !is_diagnostic(l) ? found : diagnostics_only).push_back(&l);
  if (found.empty() && !diagnostics_only.empty())
    throw InputError(
        fmt::format("--require '{}': no result named '{}'; the fit diagnostic '{}' is compared only when "
                    "named with its path",
                    r.expression, r.path, diagnostics_only.front()->path));
  if (found.empty())
    throw InputError(fmt::format("--require '{}': no number named '{}' in the results", r.expression, r.path));
  // Prefer a number that is not inside an array (a pooled or summary value over one of a
  // list), then the shortest path, then a fitted parameter (a member of a "params" object).
  auto is_param = [](const RequirementLeaf* l) {
    return l->segments.size() >= 2 && l->segments[l->segments.size() - 2] == "params";
  };
  auto in_array = [](const RequirementLeaf* l) {
    return std::any_of(l->segments.begin(), l->segments.end(), [](const std::string& s) { return s.front() == '['; });
  };
  auto key = [&](const RequirementLeaf* l) { return std::make_tuple(in_array(l), l->segments.size(), !is_param(l)); };
  std::stable_sort(found.begin(), found.end(),
                   [&](const RequirementLeaf* a, const RequirementLeaf* b) { return key(a) < key(b); });
  std::vector<std::string> ties;
  for (const RequirementLeaf* l : found)
    if (key(l) == key(found.front()) && l->value != found.front()->value) ties.push_back(l->path);
  if (!ties.empty()) {
    std::string list = found.front()->path;
    for (const auto& t : ties) list += ", " + t;
    throw InputError(
        fmt::format("--require '{}': '{}' is ambiguous ({}); give a longer path", r.expression, r.path, list));
  }
  RequirementOutcome o;
  o.requirement = r;
  o.resolved_path = found.front()->path;
  o.pointer = found.front()->pointer;
  o.value = found.front()->value;
  const double v = o.value, t = r.threshold;
  if (r.op == "<") o.met = v < t;
  else if (r.op == "<=") o.met = v <= t;
  else if (r.op == ">") o.met = v > t;
  else if (r.op == ">=") o.met = v >= t;
  else if (r.op == "==") o.met = v == t;
  else o.met = v != t;
  return o;
}

}  // namespace tunekit::calibration
