// tunekit belts: compare the two belts of a CoreXY machine from one pluck recording of each:
// each belt's fundamental frequency (ring-down analysis, ident/ringdown.hpp), their difference,
// the tension ratio (fA / fB)^2 and, with the span and the belt, each belt's tension in newtons
// (taut-string model, ident/belt_tension.hpp) and what to tighten.
#include <cmath>
#include <memory>

#include <fmt/format.h>

#include "resonance_json.hpp"
#include "tunekit/fitting/stats.hpp"
#include "tunekit/calibration/analyses/belts_command.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/file_bytes.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/machine/machine_profile.hpp"

namespace tunekit::calibration {
namespace {

// Fills what the options leave open from the profile's [belts] section; checks the values.
void resolve_belt_options(BeltsOptions& a, std::vector<InputDigest>& inputs) {
  if (!a.profile.empty()) {
    const std::string bytes = read_file_bytes(a.profile);
    inputs.push_back(input_digest(a.profile, bytes));
    const auto p = machine::parse_machine_profile(bytes, a.profile);
    if (a.belt.empty()) a.belt = p.belts.belt;
    if (!(a.belt_mass_g_m > 0)) a.belt_mass_g_m = p.belts.mass_g_m;
    if (!(a.span_mm > 0)) a.span_mm = p.belts.span_mm;
    if (p.belts.span_uncertainty_mm > 0) a.span_uncertainty_mm = p.belts.span_uncertainty_mm;
    if (!(a.target_n > 0)) a.target_n = p.belts.target_n;
  }
  if (a.span_mm < 0 || !std::isfinite(a.span_mm)) throw InputError("--span-mm must be positive");
  if (a.span_uncertainty_mm < 0 || !std::isfinite(a.span_uncertainty_mm))
    throw InputError("--span-uncertainty-mm must be zero or positive");
  if (a.target_n < 0 || !std::isfinite(a.target_n)) throw InputError("--target-n must be positive");
  if (a.belt_mass_g_m < 0 || !std::isfinite(a.belt_mass_g_m)) throw InputError("--belt-mass-g-m must be positive");
  if (!a.belt.empty()) (void)ident::belt_spec(a.belt);  // InputError naming the known belts
  if (a.target_n > 0 && !(a.span_mm > 0))
    throw InputError("a target tension needs the free span: give --span-mm (or [belts] span_mm in the profile)");
}

double belt_mass_kg_m(const BeltsOptions& a) {
  if (a.belt_mass_g_m > 0) return a.belt_mass_g_m * 1e-3;
  return ident::belt_spec(a.belt.empty() ? std::string("gt2-6mm") : a.belt).mass_kg_m;
}

std::string one_belt_advice(char name, const ident::RingdownResult& r, const BeltTension& t, double target_n) {
  const auto& s = t.tension;
  if (target_n >= s.ci95_lo && target_n <= s.ci95_hi)
    return fmt::format("belt {} is at the target: {:.1f} N [{:.1f}, {:.1f}] for {:.1f} N", name, s.tension_n, s.ci95_lo,
                       s.ci95_hi, target_n);
  return fmt::format("{} belt {} by about {:.1f} N: from {:.1f} N ({:.1f} Hz) to {:.1f} N ({:.1f} Hz)",
                     s.tension_n < target_n ? "tighten" : "loosen", name, std::abs(target_n - s.tension_n), s.tension_n,
                     r.damped_freq_hz, target_n, t.target_hz);
}

void belts_advice(BeltsOutcome& o) {
  if (o.tension_a && o.tension_b && o.options.target_n > 0) {
    o.advice.push_back(one_belt_advice('A', o.a, *o.tension_a, o.options.target_n));
    o.advice.push_back(one_belt_advice('B', o.b, *o.tension_b, o.options.target_n));
    return;
  }
  const bool a_tighter = o.difference_hz > 0;
  const char loose = a_tighter ? 'B' : 'A', tight = a_tighter ? 'A' : 'B';
  const auto& rl = a_tighter ? o.b : o.a;
  const auto& rt = a_tighter ? o.a : o.b;
  if (o.tension_a && o.tension_b) {
    if (std::abs(o.difference_n) <= fitting::kZ95 * o.difference_stderr_n) {
      o.advice.push_back(fmt::format("the belts agree within their uncertainty: A - B = {:+.1f} N [{:+.1f}, {:+.1f}]",
                                     o.difference_n, o.difference_n - fitting::kZ95 * o.difference_stderr_n,
                                     o.difference_n + fitting::kZ95 * o.difference_stderr_n));
      return;
    }
    o.advice.push_back(
        fmt::format("tighten belt {} by about {:.1f} N (from {:.1f} Hz to {:.1f} Hz) to match belt {}, "
                    "or loosen belt {} by as much",
                    loose, std::abs(o.difference_n), rl.damped_freq_hz, rt.damped_freq_hz, tight, tight));
    return;
  }
  if (std::abs(o.difference_hz) <= fitting::kZ95 * o.difference_stderr_hz) {
    o.advice.push_back(fmt::format("the belts agree within their uncertainty: A - B = {:+.2f} Hz", o.difference_hz));
    return;
  }
  o.advice.push_back(
      fmt::format("tighten belt {} until it rings at {:.1f} Hz (now {:.1f} Hz) to match belt {}; give "
                  "--span-mm for tensions in newtons",
                  loose, rt.damped_freq_hz, rl.damped_freq_hz, tight));
}

nlohmann::json tension_json(const BeltTension& t) {
  const auto& s = t.tension;
  nlohmann::json j{{"value", s.tension_n}, {"stderr", s.stderr_n}, {"ci95", {s.ci95_lo, s.ci95_hi}}, {"unit", "N"}};
  if (t.target_hz > 0) j["target_freq_hz"] = t.target_hz;
  return j;
}

}  // namespace

ident::RingdownOptions belts_ringdown_defaults() {
  ident::RingdownOptions o;
  o.min_hz = 40;
  o.max_zeta = 0.06;
  return o;
}

BeltsOutcome compute_belts(const BeltsOptions& opts) {
  BeltsOutcome o;
  o.options = opts;
  BeltsOptions& a = o.options;
  check_ringdown_options(a.ringdown);
  std::vector<InputDigest> profile_digest;
  resolve_belt_options(a, profile_digest);
  ident::AccelInputOptions in = a.input;
  in.axis = 'x';  // not used: a belt record is not an axis measurement
  auto analyse = [&](const std::string& path) {
    const std::string bytes = read_file_bytes(path);
    o.inputs.push_back(input_digest(path, bytes));
    const auto rec = ident::load_accel_csv(path, bytes, in);
    for (const auto& w : rec.warnings) o.warnings.push_back(path + ": " + w);
    auto r = ident::analyze_ringdown(rec, a.ringdown);
    for (const auto& w : r.warnings) o.warnings.push_back(path + ": " + w);
    return r;
  };
  o.a = analyse(a.file_a);
  o.b = analyse(a.file_b);
  for (auto& d : profile_digest) o.inputs.push_back(std::move(d));
  const double fa = o.a.damped_freq_hz, fb = o.b.damped_freq_hz;
  const double sa = o.a.freq_stderr_hz, sb = o.b.freq_stderr_hz;
  o.difference_hz = fa - fb;
  o.difference_stderr_hz = std::hypot(sa, sb);
  o.tension_ratio = (fa / fb) * (fa / fb);
  // Delta method: d ln(ratio) = 2 (d fa / fa - d fb / fb).
  o.tension_ratio_stderr = o.tension_ratio * 2 * std::hypot(sa / fa, sb / fb);
  if (a.span_mm > 0) {
    o.mass_kg_m = belt_mass_kg_m(a);
    const double span_m = a.span_mm * 1e-3, span_se = a.span_uncertainty_mm * 1e-3;
    auto tension = [&](const ident::RingdownResult& r) {
      BeltTension t;
      t.tension = ident::string_tension(o.mass_kg_m, span_m, span_se, r.damped_freq_hz, r.freq_stderr_hz);
      if (a.target_n > 0) t.target_hz = ident::string_frequency(o.mass_kg_m, span_m, a.target_n);
      return t;
    };
    o.tension_a = tension(o.a);
    o.tension_b = tension(o.b);
    // The span is common to both belts: the difference's uncertainty is the frequencies' alone.
    const double k = 4 * o.mass_kg_m * span_m * span_m;
    o.difference_n = o.tension_a->tension.tension_n - o.tension_b->tension.tension_n;
    const double se_from_f = k * 2 * std::hypot(fa * sa, fb * sb);
    const double se_from_l = std::abs(o.difference_n) * 2 * (span_m > 0 ? span_se / span_m : 0.0);
    o.difference_stderr_n = std::hypot(se_from_f, se_from_l);
  }
  belts_advice(o);
  return o;
}

Envelope to_envelope(const BeltsOutcome& o) {
  const BeltsOptions& a = o.options;
  Envelope env("belts");
  env.set_options({{"time_column", a.input.time_column},
                   {"accel_columns", a.input.accel_columns},
                   {"channel", a.ringdown.channel},
                   {"min_strength", a.ringdown.min_strength},
                   {"ringdown_min_hz", a.ringdown.min_hz},
                   {"ringdown_max_hz", a.ringdown.max_hz},
                   {"max_zeta", a.ringdown.max_zeta},
                   {"profile", a.profile},
                   {"belt", a.belt},
                   {"belt_mass_g_m", a.belt_mass_g_m},
                   {"span_mm", a.span_mm},
                   {"span_uncertainty_mm", a.span_uncertainty_mm},
                   {"target_n", a.target_n}});
  for (const auto& d : o.inputs) add_input(env, d);
  for (const auto& w : o.warnings) env.warn(w);
  const double diff = o.difference_hz, diff_se = o.difference_stderr_hz;
  const double ratio = o.tension_ratio, ratio_se = o.tension_ratio_stderr;
  auto& res = env.results();
  res["a"] = ident::to_json(o.a);
  res["b"] = ident::to_json(o.b);
  res["freq_a_hz"] = o.a.damped_freq_hz;
  res["freq_b_hz"] = o.b.damped_freq_hz;
  res["difference_hz"] = diff;
  res["difference_stderr_hz"] = diff_se;
  res["difference_ci95"] = {diff - fitting::kZ95 * diff_se, diff + fitting::kZ95 * diff_se};
  res["tension_ratio"] = ratio;
  res["tension_ratio_stderr"] = ratio_se;
  res["tension_ratio_ci95"] = {ratio - fitting::kZ95 * ratio_se, ratio + fitting::kZ95 * ratio_se};
  res["units"] = {{"freq", "Hz"}, {"tension_ratio", "1"}, {"tension", "N"}};
  if (o.tension_a && o.tension_b) {
    res["belt"] = {{"type", a.belt_mass_g_m > 0 ? std::string() : (a.belt.empty() ? std::string("gt2-6mm") : a.belt)},
                   {"mass_kg_m", o.mass_kg_m},
                   {"span_mm", a.span_mm},
                   {"span_uncertainty_mm", a.span_uncertainty_mm},
                   {"model", "T = 4 mu L^2 f^2 (taut string)"}};
    res["tension_a_n"] = tension_json(*o.tension_a);
    res["tension_b_n"] = tension_json(*o.tension_b);
    res["difference_n"] = o.difference_n;
    res["difference_stderr_n"] = o.difference_stderr_n;
    res["difference_n_ci95"] = {o.difference_n - fitting::kZ95 * o.difference_stderr_n,
                                o.difference_n + fitting::kZ95 * o.difference_stderr_n};
    if (a.target_n > 0) res["target_n"] = a.target_n;
  }
  res["advice"] = o.advice;
  return env;
}

void print_text(const BeltsOutcome& o, std::ostream& os) {
  auto line = [&](char name, const std::string& file, const ident::RingdownResult& r,
                  const std::optional<BeltTension>& t) {
    std::string harmonics;
    for (const auto& h : r.harmonics)
      if (h.k > 1) harmonics += fmt::format("{}{}x {:.1f} Hz", harmonics.empty() ? "" : ", ", h.k, h.freq_hz);
    const double to_damped = r.freq_hz > 0 ? r.damped_freq_hz / r.freq_hz : 1.0;  // the interval with its value
    os << fmt::format("belt {} ({}): {:.2f} Hz [{:.2f}, {:.2f}]", name, file, r.damped_freq_hz,
                      to_damped * r.freq_ci95_lo, to_damped * r.freq_ci95_hi);
    if (t)
      os << fmt::format("   {:.1f} N [{:.1f}, {:.1f}]", t->tension.tension_n, t->tension.ci95_lo, t->tension.ci95_hi);
    os << fmt::format("\n  from {} (strength {:.1f}), harmonics: {}\n", r.projection, r.strength,
                      harmonics.empty() ? std::string("none found") : harmonics);
  };
  line('A', o.options.file_a, o.a, o.tension_a);
  line('B', o.options.file_b, o.b, o.tension_b);
  const double diff = o.difference_hz, diff_se = o.difference_stderr_hz;
  os << fmt::format("difference A - B: {:+.2f} Hz [{:+.2f}, {:+.2f}]   tension ratio (fA/fB)^2: {:.3f}\n", diff,
                    diff - fitting::kZ95 * diff_se, diff + fitting::kZ95 * diff_se, o.tension_ratio);
  if (o.tension_a)
    os << fmt::format("tensions from T = 4 mu L^2 f^2: mu {:.4g} g/m, span {:g} +- {:g} mm\n", o.mass_kg_m * 1e3,
                      o.options.span_mm, o.options.span_uncertainty_mm);
  for (const auto& s : o.advice) os << s << "\n";
}

}  // namespace tunekit::calibration
