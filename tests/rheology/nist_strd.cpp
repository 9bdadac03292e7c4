#include "nist_strd.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include <ceres/jet.h>

#include "tunekit/core/error.hpp"
#include "tunekit/core/file_bytes.hpp"

namespace tunekit::fitting {
namespace {

constexpr int kMaxParams = 8;
using Jet = ceres::Jet<double, kMaxParams>;

template <class T>
T eval_model(const std::string& name, const T* b, double x) {
  using ceres::atan;
  using ceres::exp;
  using ceres::pow;
  using std::atan;
  using std::exp;
  using std::pow;
  const T one(1.0);
  if (name == "Misra1a" || name == "BoxBOD") return b[0] * (one - exp(-b[1] * x));
  if (name == "Misra1b") return b[0] * (one - pow(one + b[1] * x / 2.0, -2.0));
  if (name == "Misra1c") return b[0] * (one - pow(one + 2.0 * b[1] * x, -0.5));
  if (name == "Misra1d") return b[0] * b[1] * x / (one + b[1] * x);
  if (name == "Chwirut1" || name == "Chwirut2") return exp(-b[0] * x) / (b[1] + b[2] * x);
  if (name == "DanWood") return b[0] * pow(T(x), b[1]);
  if (name == "Eckerle4") {
    const T z = (x - b[2]) / b[1];
    return (b[0] / b[1]) * exp(-0.5 * z * z);
  }
  if (name == "Rat42") return b[0] / (one + exp(b[1] - b[2] * x));
  if (name == "Rat43") return b[0] / pow(one + exp(b[1] - b[2] * x), one / b[3]);
  if (name == "MGH09") return b[0] * (x * x + x * b[1]) / (x * x + x * b[2] + b[3]);
  if (name == "MGH10") return b[0] * exp(b[1] / (x + b[2]));
  if (name == "MGH17") return b[0] + b[1] * exp(-x * b[3]) + b[2] * exp(-x * b[4]);
  if (name == "Thurber" || name == "Hahn1")
    return (b[0] + b[1] * x + b[2] * x * x + b[3] * x * x * x) / (one + b[4] * x + b[5] * x * x + b[6] * x * x * x);
  if (name == "Kirby2") return (b[0] + b[1] * x + b[2] * x * x) / (one + b[3] * x + b[4] * x * x);
  if (name == "Bennett5") return b[0] * pow(b[1] + x, -one / b[2]);
  if (name == "Lanczos1" || name == "Lanczos2" || name == "Lanczos3")
    return b[0] * exp(-b[1] * x) + b[2] * exp(-b[3] * x) + b[4] * exp(-b[5] * x);
  if (name == "Gauss1" || name == "Gauss2" || name == "Gauss3") {
    const T u = x - b[3], w = x - b[6];
    return b[0] * exp(-b[1] * x) + b[2] * exp(-u * u / (b[4] * b[4])) + b[5] * exp(-w * w / (b[7] * b[7]));
  }
  if (name == "Roszman1") return b[0] - b[1] * x - atan(b[2] / (x - b[3])) / std::numbers::pi;
  throw InputError("NIST problem '" + name + "' has no model in tunekit");
}

std::vector<double> numbers_in(const std::string& s) {
  std::vector<double> v;
  std::istringstream is(s);
  std::string tok;
  while (is >> tok) {
    char* end = nullptr;
    const double d = std::strtod(tok.c_str(), &end);
    if (end != tok.c_str() && *end == '\0') v.push_back(d);
  }
  return v;
}

}  // namespace

NistProblem read_nist_problem(const std::string& path) {
  std::istringstream in(read_file_bytes(path));
  NistProblem p;
  std::string line;
  std::size_t ln = 0;
  bool in_data = false;
  while (std::getline(in, line)) {
    ++ln;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (in_data) {
      const auto v = numbers_in(line);
      if (v.empty()) continue;
      if (v.size() != 2) throw InputError("expected 'y x' on a data line", path + ":" + std::to_string(ln));
      p.y.push_back(v[0]);
      p.x.push_back(v[1]);
      continue;
    }
    if (line.rfind("Dataset Name:", 0) == 0) {
      std::istringstream is(line.substr(13));
      is >> p.name;
    } else if (line.find("Level of Difficulty") != std::string::npos) {
      std::istringstream is(line);
      is >> p.difficulty;
    } else if (line.rfind("Residual Sum of Squares:", 0) == 0) {
      p.certified_rss = numbers_in(line.substr(24)).at(0);
    } else if (line.rfind("Residual Standard Deviation:", 0) == 0) {
      p.certified_residual_sd = numbers_in(line.substr(28)).at(0);
    } else if (line.rfind("Data:", 0) == 0 && line.find(" y ") != std::string::npos) {
      in_data = true;
    } else {
      const auto eq = line.find('=');
      std::string lhs = line.substr(0, eq == std::string::npos ? 0 : eq);
      lhs.erase(std::remove(lhs.begin(), lhs.end(), ' '), lhs.end());
      if (eq != std::string::npos && lhs.size() >= 2 && lhs[0] == 'b' &&
          std::isdigit(static_cast<unsigned char>(lhs[1]))) {
        const auto v = numbers_in(line.substr(eq + 1));
        if (v.size() != 4)
          throw InputError("expected start 1, start 2, value, std. deviation", path + ":" + std::to_string(ln));
        p.start1.push_back(v[0]);
        p.start2.push_back(v[1]);
        p.certified.push_back(v[2]);
        p.certified_sd.push_back(v[3]);
      }
    }
  }
  if (p.name.empty() || p.certified.empty() || p.x.empty())
    throw InputError("not a NIST StRD nonlinear regression file (no name, parameters or data)", path);
  if (p.certified.size() > static_cast<std::size_t>(kMaxParams)) throw InputError("too many parameters", path);
  const double b0[kMaxParams] = {1, 1, 1, 1, 1, 1, 1, 1};
  (void)eval_model<double>(p.name, b0, 1.0);  // throws for an unknown model
  return p;
}

LsqProblem nist_lsq_problem(const NistProblem& p, const std::vector<double>& start) {
  LsqProblem lp;
  for (std::size_t j = 0; j < start.size(); ++j) lp.params.push_back({"b" + std::to_string(j + 1), "1", start[j]});
  lp.num_residuals = static_cast<int>(p.x.size());
  lp.observed = p.y;
  lp.residuals_are_time_ordered = false;
  const auto k = static_cast<int>(start.size());
  lp.residuals_and_jacobian = [&p, k](const double* b, double* r, double* J) {
    if (J == nullptr) {
      for (std::size_t i = 0; i < p.x.size(); ++i) r[i] = eval_model<double>(p.name, b, p.x[i]) - p.y[i];
    } else {
      Jet bj[kMaxParams];
      for (int j = 0; j < k; ++j) bj[j] = Jet(b[j], j);
      for (std::size_t i = 0; i < p.x.size(); ++i) {
        const Jet f = eval_model<Jet>(p.name, bj, p.x[i]);
        r[i] = f.a - p.y[i];
        for (int j = 0; j < k; ++j) J[i * k + j] = f.v[j];
      }
    }
    for (std::size_t i = 0; i < p.x.size(); ++i)
      if (!std::isfinite(r[i])) return false;
    return true;
  };
  return lp;
}

LsqOptions nist_lsq_options() {
  LsqOptions o;
  o.max_iterations = 20000;
  o.function_tolerance = 1e-16;
  o.gradient_tolerance = 1e-20;
  o.parameter_tolerance = 1e-16;
  o.min_reciprocal_condition = 1e-30;
  return o;
}

double log_relative_error(double est, double cert) {
  if (!std::isfinite(est)) return 0;
  const double diff = std::abs(est - cert);
  if (diff == 0) return 11;
  const double lre = cert != 0 ? -std::log10(diff / std::abs(cert)) : -std::log10(diff);
  return std::clamp(lre, 0.0, 11.0);
}

NistOutcome solve_nist_problem(const NistProblem& p, int start, bool global) {
  NistOutcome o;
  o.problem = p.name;
  o.start = start;
  o.global_search = global;
  const auto& s = start == 1 ? p.start1 : p.start2;
  LsqProblem lp = nist_lsq_problem(p, s);
  try {
    FitResult fit;
    if (global) {
      for (std::size_t j = 0; j < s.size(); ++j) {
        const double a = s[j] / 1000, b = s[j] * 1000;
        lp.params[j].lower = std::min(a, b);
        lp.params[j].upper = std::max(a, b);
        if (s[j] == 0) lp.params[j].lower = -1, lp.params[j].upper = 1;
      }
      GlobalStartOptions go;
      go.max_evaluations = 20000;
      go.extra_starts = {s};
      const auto gs = global_start(lp, go);
      for (std::size_t j = 0; j < s.size(); ++j) {
        lp.params[j].start = gs.start[j];
        lp.params[j].lower = -std::numeric_limits<double>::infinity();
        lp.params[j].upper = std::numeric_limits<double>::infinity();
      }
    }
    fit = solve_least_squares(p.name, lp, nist_lsq_options());
    o.solved = true;
    o.iterations = fit.diagnostics.iterations;
    o.min_lre_params = 11;
    o.min_lre_sd = 11;
    for (std::size_t j = 0; j < s.size(); ++j) {
      o.estimate.push_back(fit.params[j].value);
      o.std_error.push_back(fit.params[j].std_error);
      o.min_lre_params = std::min(o.min_lre_params, log_relative_error(fit.params[j].value, p.certified[j]));
      o.min_lre_sd = std::min(o.min_lre_sd, log_relative_error(fit.params[j].std_error, p.certified_sd[j]));
    }
    o.lre_rss = log_relative_error(fit.diagnostics.rss, p.certified_rss);
  } catch (const Error& e) {
    o.error = e.message();
  }
  return o;
}

}  // namespace tunekit::fitting
