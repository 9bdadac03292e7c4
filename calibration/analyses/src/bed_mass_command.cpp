// tunekit resonance --load-kg: the bed axis' f(m) from sweeps with known masses on the bed, its
// predictions and the schedule it gives each firmware.
#include "tunekit/calibration/analyses/bed_mass_command.hpp"

#include <cmath>
#include <iterator>

#include <fmt/format.h>

#include "tunekit/calibration/presentation/bed_mass_plot.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/file_bytes.hpp"
#include "tunekit/design/bed_mass_schedule.hpp"
#include "tunekit/firmware/firmware_limits.hpp"

namespace tunekit::calibration {
namespace {

constexpr double kGramsPerKg = 1000;

/// One record's first mode as `tunekit resonance` identifies it.
BedMassRecord sweep_point(const BedMassOptions& o, const std::string& file, double load_kg, BedMassOutcome& out) {
  AccelFilesOptions a = o.accel;
  a.files = {file};
  AccelAnalysis an = analyze_accel_files(a);
  for (auto& d : an.inputs) out.inputs.push_back(d);
  for (auto& w : an.warnings) out.warnings.push_back(fmt::format("{}: {}", file, w));
  if (an.axes.empty() || an.axes.front().modes.modes.empty())
    throw FitError(fmt::format("{}: no mode was found in the record", file));
  const auto& modes = an.axes.front().modes;
  const auto& m = modes.modes.front();  // the lowest: the bed moving on its belt
  BedMassRecord r;
  r.point = {load_kg, m.freq_hz, m.freq_stderr_hz, m.zeta, m.zeta_stderr, file};
  r.method = modes.method;
  return r;
}

void check_options(const BedMassOptions& o) {
  if (o.accel.files.size() != o.loads_kg.size())
    throw InputError(fmt::format("--load-kg: {} masses for {} records (give one mass per record, in order)",
                                 o.loads_kg.size(), o.accel.files.size()));
  if (o.held_out.size() != o.held_out_loads_kg.size())
    throw InputError(fmt::format("--held-out-load-kg: {} masses for {} held-out records", o.held_out_loads_kg.size(),
                                 o.held_out.size()));
  if (!o.gcode_in.empty() != !o.gcode_out.empty()) throw InputError("--gcode-in and --gcode-out go together");
  if (o.gcode_firmware != "klipper" && o.gcode_firmware != "kalico" && o.gcode_firmware != "prusa")
    throw InputError(fmt::format("--gcode-firmware {}: klipper, kalico or prusa", o.gcode_firmware));
}

void firmware_lines(const BedMassOptions& o, BedMassOutcome& out) {
  const double mass_g = std::isfinite(o.print_mass_g) ? o.print_mass_g : out.gcode ? out.gcode->print_mass_g : 0.0;
  if (!(mass_g > 0)) return;
  out.schedule = design::linear_schedule(out.fit.model, mass_g);
  const auto& s = *out.schedule;
  // ftMotionShaper_t's code: the shaper's place in ft_types.h's order (firmware_limits.hpp).
  int code = 0;
  for (std::size_t i = 0; i < std::size(firmware::limits::kMarlinFtMotionShapers); ++i)
    if (o.shaper == firmware::limits::kMarlinFtMotionShapers[i].tunekit_name) code = static_cast<int>(i) + 1;
  if (code == 0)
    throw InputError(
        fmt::format("--schedule-shaper {}: Marlin's FT_MOTION has zv, zvd, zvdd, ei, 2hump_ei, "
                    "3hump_ei and mzv",
                    o.shaper));

  out.marlin_lines = firmware::marlin_mass_schedule_lines(firmware::parse_m493_syntax(o.marlin_m493_form), code,
                                                          o.shaper_zeta, s, out.grams_per_mm);
  if (o.shaper == "zvdd" || o.shaper == "zvddd")
    out.warnings.push_back(fmt::format("Prusa's M593 has no {} shaper: no Prusa lines", o.shaper));
  else out.prusa_lines = firmware::prusa_weight_adjust_lines(o.shaper, o.shaper_zeta, s);
  if (s.max_deviation_hz > o.step_hz)
    out.warnings.push_back(fmt::format(
        "the straight line Marlin and Prusa take is {:.2f} Hz off f(m) at {:.0f} g (more than the {:g} Hz step)",
        s.max_deviation_hz, s.max_deviation_at_g, o.step_hz));
  if (out.gcode && out.gcode->resets_e)
    out.warnings.push_back(
        "the sliced file resets E (G92 E) while printing: Marlin's M493 D2 takes the extruder's position as the mass, "
        "so its schedule restarts at each reset; slice without E resets for it");
}

}  // namespace

BedMassOutcome compute_bed_mass(const BedMassOptions& o) {
  check_options(o);
  BedMassOutcome out;
  out.options = o;
  out.grams_per_mm = design::filament_grams_per_mm(o.filament_diameter_mm, o.filament_density_g_cm3);
  std::vector<ident::BedMassPoint> points;
  for (std::size_t i = 0; i < o.accel.files.size(); ++i) {
    out.records.push_back(sweep_point(o, o.accel.files[i], o.loads_kg[i], out));
    points.push_back(out.records.back().point);
  }
  out.fit = ident::fit_bed_mass(points);
  for (const auto& w : out.fit.warnings) out.warnings.push_back(w);
  for (std::size_t i = 0; i < o.held_out.size(); ++i)
    out.held_out.push_back(
        ident::check_held_out(out.fit.model, sweep_point(o, o.held_out[i], o.held_out_loads_kg[i], out).point));
  for (double g : o.predict_g) out.predictions.push_back(out.fit.model.predict(g / kGramsPerKg));
  if (!o.gcode_in.empty()) {
    const std::string text = read_file_bytes(o.gcode_in);
    out.inputs.push_back(input_digest(o.gcode_in, text));
    firmware::GcodeMassScheduleOptions go;
    go.command = o.gcode_firmware == "prusa" ? firmware::MassScheduleCommand::prusa_m74
                                             : firmware::MassScheduleCommand::set_input_shaper;
    go.grams_per_mm = out.grams_per_mm;
    go.min_step_hz = o.step_hz;
    out.gcode = firmware::apply_gcode_mass_schedule(text, out.fit.model, go, o.gcode_in);
  }
  firmware_lines(o, out);
  if (out.gcode) core::write_file_atomic(o.gcode_out, out.gcode->text);
  if (!o.plot.empty())
    render_figure(bed_mass_figure(out.fit, out.held_out, out.gcode ? out.gcode->layer_mass_g : std::vector<double>{}),
                  o.plot);
  return out;
}

namespace {

nlohmann::json prediction_json(const ident::BedFrequencyPrediction& p) {
  return {{"added_mass_kg", p.added_mass_kg},
          {"freq_hz", p.freq_hz},
          {"freq_stderr_hz", p.stderr_hz},
          {"freq_ci95", {p.ci95_lo_hz, p.ci95_hi_hz}}};
}

nlohmann::json point_json(const ident::BedMassPoint& p) {
  return {{"file", p.source},     {"added_mass_kg", p.added_mass_kg},
          {"freq_hz", p.freq_hz}, {"freq_stderr_hz", p.freq_stderr_hz},
          {"zeta", p.zeta},       {"zeta_stderr", p.zeta_stderr}};
}

nlohmann::json schedule_json(const BedMassOutcome& out) {
  nlohmann::json j;
  const auto& s = *out.schedule;
  j["print_mass_g"] = s.print_mass_g;
  j["base_hz"] = s.base_hz;
  j["end_hz"] = s.end_hz;
  j["slope_hz_per_g"] = s.slope_hz_per_g;
  j["line_max_deviation_hz"] = s.max_deviation_hz;
  j["line_max_deviation_at_g"] = s.max_deviation_at_g;
  j["marlin"] = {{"hz_per_mm_filament", firmware::marlin_hz_per_mm(s, out.grams_per_mm)},
                 {"m493_form", out.options.marlin_m493_form},
                 {"gcode", out.marlin_lines}};
  j["prusa"] = {{"gcode", out.prusa_lines}};
  return j;
}

}  // namespace

Envelope to_envelope(const BedMassOutcome& out) {
  Envelope env("resonance");
  const auto& o = out.options;
  env.set_options({{"load_kg", o.loads_kg},
                   {"held_out_load_kg", o.held_out_loads_kg},
                   {"filament_diameter_mm", o.filament_diameter_mm},
                   {"filament_density_g_cm3", o.filament_density_g_cm3},
                   {"step_hz", o.step_hz}});
  for (const auto& d : out.inputs) add_input(env, d);
  for (const auto& w : out.warnings) env.warn(w);
  auto& r = env.results();
  nlohmann::json pts = nlohmann::json::array();
  for (const auto& rec : out.records) pts.push_back(point_json(rec.point));
  const auto& f = out.fit;
  r["bed_mass"] = {{"model", "f = sqrt(k / (m0 + m)) / (2 pi)"},
                   {"fit", fitting::to_json(f.fit)},
                   {"correlation", f.model.correlation()},
                   {"chi_square", f.chi_square},
                   {"dof", f.dof},
                   {"points", pts}};
  r["bed_mass"]["damping"] = {{"zeta0", f.damping.zeta0},
                              {"slope_per_kg", f.damping.slope_per_kg},
                              {"slope_stderr_per_kg", f.damping.slope_stderr_per_kg},
                              {"slope_ci95", {f.damping.slope_ci95_lo, f.damping.slope_ci95_hi}},
                              {"damping_N_s_per_m", f.damping.damping_N_s_per_m},
                              {"mean_damping_N_s_per_m", f.damping.mean_damping_N_s_per_m}};
  nlohmann::json ho = nlohmann::json::array();
  for (const auto& h : out.held_out)
    ho.push_back({{"measured", point_json(h.point)},
                  {"predicted", prediction_json(h.predicted)},
                  {"error_hz", h.error_hz},
                  {"relative_error", h.relative_error},
                  {"z", h.z}});
  r["bed_mass"]["held_out"] = ho;
  nlohmann::json pr = nlohmann::json::array();
  for (const auto& p : out.predictions) pr.push_back(prediction_json(p));
  r["bed_mass"]["predictions"] = pr;
  r["bed_mass"]["filament_g_per_mm"] = out.grams_per_mm;
  if (out.schedule) r["bed_mass"]["schedule"] = schedule_json(out);
  if (out.gcode) {
    nlohmann::json ch = nlohmann::json::array();
    for (const auto& c : out.gcode->changes)
      ch.push_back({{"line", c.line}, {"layer", c.layer}, {"mass_g", c.mass_g}, {"freq_hz", c.freq_hz}});
    r["bed_mass"]["gcode_post"] = {{"in", o.gcode_in},
                                   {"out", o.gcode_out},
                                   {"firmware", o.gcode_firmware},
                                   {"layers", out.gcode->layers},
                                   {"print_mass_g", out.gcode->print_mass_g},
                                   {"step_hz", o.step_hz},
                                   {"changes", ch}};
  }
  return env;
}

void print_text(const BedMassOutcome& out, std::ostream& os) {
  const auto& m = out.fit.model;
  const auto& p = out.fit.fit.params;
  os << fmt::format("bed axis f(m) = sqrt(k / (m0 + m)) / (2 pi) from {} sweeps\n", out.records.size());
  for (const auto& rec : out.records)
    os << fmt::format("  {:.3f} kg: {:.3f} Hz +- {:.2g} (zeta {:.4f})  {}\n", rec.point.added_mass_kg,
                      rec.point.freq_hz, rec.point.freq_stderr_hz, rec.point.zeta, rec.point.source);
  os << fmt::format("  m0 = {:.4f} kg  [{:.4f}, {:.4f}]\n", m.moving_mass_kg, p[0].ci95_lo, p[0].ci95_hi);
  os << fmt::format("  k  = {:.3f} N/mm  [{:.3f}, {:.3f}]   correlation(m0, k) {:.3f}\n", m.stiffness_N_per_mm,
                    p[1].ci95_lo, p[1].ci95_hi, m.correlation());
  os << fmt::format("  damping ratio {:.4f} {:+.4f}/kg (slope 95 %: [{:.4f}, {:.4f}])\n", out.fit.damping.zeta0,
                    out.fit.damping.slope_per_kg, out.fit.damping.slope_ci95_lo, out.fit.damping.slope_ci95_hi);
  for (const auto& h : out.held_out)
    os << fmt::format(
        "  held out {:.3f} kg: measured {:.3f} Hz, predicted {:.3f} Hz [{:.3f}, {:.3f}], error {:+.3f} %\n",
        h.point.added_mass_kg, h.point.freq_hz, h.predicted.freq_hz, h.predicted.ci95_lo_hz, h.predicted.ci95_hi_hz,
        100 * h.relative_error);
  for (const auto& pr : out.predictions)
    os << fmt::format("  at {:.0f} g: {:.3f} Hz [{:.3f}, {:.3f}]\n", pr.added_mass_kg * kGramsPerKg, pr.freq_hz,
                      pr.ci95_lo_hz, pr.ci95_hi_hz);
  for (const auto& l : out.marlin_lines) os << "  marlin: " << l << "\n";
  for (const auto& l : out.prusa_lines) os << "  prusa:  " << l << "\n";
  if (out.gcode)
    os << fmt::format("  {}: {} layers, {:.1f} g, {} frequency changes -> {}\n", out.options.gcode_in,
                      out.gcode->layers, out.gcode->print_mass_g, out.gcode->changes.size(), out.options.gcode_out);
}

}  // namespace tunekit::calibration
