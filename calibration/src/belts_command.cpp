// tunekit belts: compare the two belts of a CoreXY machine from one pluck recording of each,
// as the belt-comparison tools report it: each belt's fundamental frequency (ring-down
// analysis, ident/ringdown.hpp), their difference, and the tension ratio (fA / fB)^2 (a
// string's tension is proportional to its frequency squared at equal length and mass).
#include <cmath>
#include <memory>

#include <fmt/format.h>

#include "resonance_json.hpp"
#include "tunekit/calibration/belts_command.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/ident/csv.hpp"
#include "tunekit/core/file_bytes.hpp"

namespace tunekit::calibration {

ident::RingdownOptions belts_ringdown_defaults() {
  ident::RingdownOptions o;
  o.min_hz = 40;
  o.max_hz = 400;
  return o;
}

BeltsOutcome compute_belts(const BeltsOptions& a) {
  BeltsOutcome o;
  o.options = a;
  check_ringdown_options(a.ringdown);
  ident::AccelInputOptions in = a.input;
  in.axis = 'x';  // not used: a belt record is not an axis measurement
  auto analyse = [&](const std::string& path) {
    const std::string bytes = read_file_bytes(path);
    o.inputs.push_back({path, sha256_hex(bytes), bytes.size()});
    const auto rec = ident::load_accel_csv(path, bytes, in);
    for (const auto& w : rec.warnings) o.warnings.push_back(path + ": " + w);
    auto r = ident::analyze_ringdown(rec, a.ringdown);
    for (const auto& w : r.warnings) o.warnings.push_back(path + ": " + w);
    return r;
  };
  o.a = analyse(a.file_a);
  o.b = analyse(a.file_b);
  const double fa = o.a.damped_freq_hz, fb = o.b.damped_freq_hz;
  const double sa = o.a.freq_stderr_hz, sb = o.b.freq_stderr_hz;
  o.difference_hz = fa - fb;
  o.difference_stderr_hz = std::hypot(sa, sb);
  o.tension_ratio = (fa / fb) * (fa / fb);
  // Delta method: d ln(ratio) = 2 (d fa / fa - d fb / fb).
  o.tension_ratio_stderr = o.tension_ratio * 2 * std::hypot(sa / fa, sb / fb);
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
                   {"ringdown_max_hz", a.ringdown.max_hz}});
  for (const auto& d : o.inputs) env.add_input_digest(d.path, d.sha256, d.size_bytes);
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
  res["difference_ci95"] = {diff - 1.96 * diff_se, diff + 1.96 * diff_se};
  res["tension_ratio"] = ratio;
  res["tension_ratio_stderr"] = ratio_se;
  res["tension_ratio_ci95"] = {ratio - 1.96 * ratio_se, ratio + 1.96 * ratio_se};
  res["units"] = {{"freq", "Hz"}, {"tension_ratio", "1"}};
  return env;
}

void print_text(const BeltsOutcome& o, std::ostream& os) {
  const double diff = o.difference_hz, diff_se = o.difference_stderr_hz;
  os << fmt::format("belt A ({}): {:.2f} Hz +- {:.2g} ({}, strength {:.1f})\n", o.options.file_a, o.a.damped_freq_hz,
                    o.a.freq_stderr_hz, o.a.channel, o.a.strength);
  os << fmt::format("belt B ({}): {:.2f} Hz +- {:.2g} ({}, strength {:.1f})\n", o.options.file_b, o.b.damped_freq_hz,
                    o.b.freq_stderr_hz, o.b.channel, o.b.strength);
  os << fmt::format("difference A - B: {:+.2f} Hz [{:+.2f}, {:+.2f}]   tension ratio (fA/fB)^2: {:.3f}\n", diff,
                    diff - 1.96 * diff_se, diff + 1.96 * diff_se, o.tension_ratio);
}

}  // namespace tunekit::calibration
