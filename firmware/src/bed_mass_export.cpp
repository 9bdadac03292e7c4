#include "tunekit/firmware/bed_mass_export.hpp"

#include <array>
#include <cmath>

#include <fmt/format.h>

#include "export_writers.hpp"
#include "gcode_words.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/firmware/config_edit.hpp"

namespace tunekit::firmware {
namespace {

// Prusa Buddy: M593 T's shaper numbers (M593.cpp's usage) and the frequencies it does not clamp
// (input_shaper_config.hpp frequency_safe_min/max; the MINI's 150 Hz is not assumed).
constexpr std::array<const char*, 6> kPrusaShapers = {"zv", "zvd", "mzv", "ei", "2hump_ei", "3hump_ei"};
constexpr double kPrusaSafeMinHz = 10, kPrusaSafeMaxHz = 100;
constexpr double kGramsPerKg = 1000;
// Decimals of the masses written (g): M74 W and M593 M.
constexpr int kDecimalsGrams = 1;
// Decimals of Marlin's scaling (Hz per mm of filament: a few 1e-5 for a print of hundreds of
// grams, so six significant digits; fixed-point, as Marlin's parser reads every other word).
constexpr int kDecimalsHzPerMm = 10;

/// The net extrusion of every line (mm of filament) and where the layers start (line index).
struct ExtrusionTrace {
  std::vector<double> e_before;  ///< net extrusion before each line
  std::vector<std::size_t> layer_lines;
  double total_mm = 0;
  bool resets_e = false;
};

bool is_layer_mark(const std::string& line) {
  return line.rfind(";LAYER_CHANGE", 0) == 0 || line.rfind(";LAYER:", 0) == 0;
}

ExtrusionTrace trace_extrusion(const LineEditor& ed) {
  ExtrusionTrace t;
  bool rel_e = false, printing = false;
  double e = 0, net = 0;
  for (std::size_t i = 0; i < ed.size(); ++i) {
    t.e_before.push_back(net);
    const std::string& line = ed.line(i);
    if (is_layer_mark(line)) {
      t.layer_lines.push_back(i);
      printing = true;
      continue;
    }
    const std::string code = gcode_words::code(line);
    if (code.empty()) continue;
    const std::string cmd = gcode_words::command(code);
    if (cmd == "M82") rel_e = false;
    else if (cmd == "M83") rel_e = true;
    else if (cmd == "G92") {
      if (auto v = gcode_words::word(code, 'E')) e = *v, t.resets_e = t.resets_e || printing;
    } else if (cmd == "G0" || cmd == "G1" || cmd == "G00" || cmd == "G01" || cmd == "G2" || cmd == "G3") {
      if (auto v = gcode_words::word(code, 'E')) {
        const double de = rel_e ? *v : *v - e;
        e = rel_e ? e + *v : *v;
        net += de;
      }
    }
  }
  t.total_mm = net;
  return t;
}

std::string layer_command(const GcodeMassScheduleOptions& o, double mass_g, double freq_hz) {
  if (o.command == MassScheduleCommand::prusa_m74)
    return fmt::format("M74 W{} ; tunekit: Y at {} Hz", format_number(mass_g, kDecimalsGrams),
                       format_number(freq_hz, detail::kDecimalsFreq));
  return fmt::format("SET_INPUT_SHAPER SHAPER_FREQ_Y={} ; tunekit: {} g on the bed",
                     format_number(freq_hz, detail::kDecimalsFreq), format_number(mass_g, kDecimalsGrams));
}

/// The frequency a SET_INPUT_SHAPER line of the file sets on Y, if it sets one.
std::optional<double> file_frequency(const std::string& line) {
  const std::string code = gcode_words::code(line);
  if (code.empty() || gcode_words::command(code) != "SET_INPUT_SHAPER") return std::nullopt;
  return gcode_words::param(code, "SHAPER_FREQ_Y");
}

}  // namespace

double marlin_hz_per_mm(const design::LinearMassSchedule& schedule, double grams_per_mm) {
  return schedule.slope_hz_per_g * grams_per_mm;
}

std::vector<std::string> marlin_mass_schedule_lines(const M493Syntax& syntax, int shaper_code, double zeta,
                                                    const design::LinearMassSchedule& schedule, double grams_per_mm) {
  if (syntax.form == M493Form::mode)
    throw InputError(
        "Marlin's 2023 M493 (one mode for X and Y) is not written with a mass-based frequency: its letters were not "
        "checked; update Marlin (FT_MOTION with per-axis shapers)");
  FtShaperWords y{"y", shaper_code, format_number(schedule.base_hz, detail::kDecimalsFreq),
                  format_number(zeta, detail::kDecimalsZeta)};
  const M493Syntax s = syntax.form == M493Form::none ? M493Syntax{} : syntax;
  std::vector<std::string> lines = m493_set_shapers(s, {y}, true).lines;
  lines.push_back("M493 D2");
  const std::string k = format_number(marlin_hz_per_mm(schedule, grams_per_mm), kDecimalsHzPerMm);
  const bool v2 = s.form == M493Form::axis_list && s.version >= 2;
  lines.push_back(v2 ? "M493 Y F" + k : "M493 H" + k);
  return lines;
}

int prusa_shaper_type(const std::string& shaper) {
  for (std::size_t i = 0; i < kPrusaShapers.size(); ++i)
    if (shaper == kPrusaShapers[i]) return static_cast<int>(i);
  throw InputError(fmt::format("Prusa's M593 has no {} shaper (zv, zvd, mzv, ei, 2hump_ei, 3hump_ei)", shaper));
}

std::vector<std::string> prusa_weight_adjust_lines(const std::string& shaper, double zeta,
                                                   const design::LinearMassSchedule& schedule) {
  for (double f : {schedule.base_hz, schedule.end_hz})
    if (!(f >= kPrusaSafeMinHz && f <= kPrusaSafeMaxHz))
      throw InputError(
          fmt::format("Prusa's firmware clamps the shaper's frequency to {:g} .. {:g} Hz: {:.2f} Hz is "
                      "outside",
                      kPrusaSafeMinHz, kPrusaSafeMaxHz, f));
  const double delta = schedule.end_hz - schedule.base_hz;
  if (!(delta < 0))
    throw InputError("Prusa's weight adjustment takes a frequency that falls with the mass (M593 A below 0)");
  return {
      fmt::format("M593 Y T{} F{} D{}", prusa_shaper_type(shaper),
                  format_number(schedule.base_hz, detail::kDecimalsFreq), format_number(zeta, detail::kDecimalsZeta)),
      fmt::format("M593 A{} M{}", format_number(delta, detail::kDecimalsFreq),
                  format_number(schedule.print_mass_g, kDecimalsGrams))};
}

GcodeMassResult apply_gcode_mass_schedule(const std::string& text, const ident::BedMassModel& model,
                                          const GcodeMassScheduleOptions& o, const std::string& path) {
  if (!(o.grams_per_mm > 0)) throw InputError("the filament's grams per mm must be positive", path);
  const LineEditor ed(text);
  const ExtrusionTrace trace = trace_extrusion(ed);
  if (trace.layer_lines.empty())
    throw InputError(
        "no layer changes marked (';LAYER_CHANGE' of PrusaSlicer, OrcaSlicer and SuperSlicer, or Cura's ';LAYER:')",
        path);
  GcodeMassResult r;
  r.layers = trace.layer_lines.size();
  r.print_mass_g = trace.total_mm * o.grams_per_mm;
  r.resets_e = trace.resets_e;
  std::vector<double> masses;
  for (auto l : trace.layer_lines) masses.push_back(trace.e_before[l] * o.grams_per_mm);
  r.layer_mass_g = masses;
  double active = std::isfinite(o.configured_hz) ? o.configured_hz : model.freq_hz(0);
  LineEditor out(text);
  std::size_t from = 0;
  for (std::size_t layer = 0; layer < masses.size(); ++layer) {
    // The file's own SET_INPUT_SHAPER lines before this layer set the active value.
    for (; from <= trace.layer_lines[layer]; ++from)
      if (auto f = file_frequency(ed.line(from))) active = *f;
    const double f = model.freq_hz(masses[layer] / kGramsPerKg);
    if (std::abs(f - active) <= o.min_step_hz) continue;
    const std::string cmd = layer_command(o, masses[layer], f);
    out.insert_before(trace.layer_lines[layer] + 1, {cmd});
    active = std::stod(format_number(f, detail::kDecimalsFreq));
    r.changes.push_back({trace.layer_lines[layer] + 1, layer, masses[layer], active, cmd});
  }
  r.text = out.render();
  return r;
}

}  // namespace tunekit::firmware
