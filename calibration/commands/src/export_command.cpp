// tunekit export: design pressure/linear advance and input shaping from the JSON results of
// `tunekit step`, `freq`, `shaper` and `rheo` (or values on the command line) and write them
// into a Klipper printer.cfg, a Marlin Configuration_adv.h or a RepRapFirmware config.g.
// By default only a unified diff is printed; --write applies it (backup + atomic rename).
// The command line (options, help) is apps/cli/src/export_cli.cpp; option parsing is export_options.cpp.
#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>

#include <fmt/format.h>

#include "export_design.hpp"
#include "export_thermal.hpp"
#include "tunekit/calibration/presentation/report.hpp"
#include "tunekit/calibration/commands/design_inputs.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/commands/export_command.hpp"
#include "tunekit/calibration/results/json_access.hpp"
#include "tunekit/calibration/presentation/plots.hpp"
#include "tunekit/calibration/results/results_json.hpp"
#include "tunekit/calibration/results/agreement.hpp"
#include "tunekit/calibration/results/calibration_record.hpp"
#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/file_bytes.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/design/flow_advance.hpp"
#include "tunekit/design/pressure_advance.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/core/file_lock.hpp"
#include "tunekit/core/text.hpp"
#include "tunekit/firmware/config_edit.hpp"
#include "tunekit/firmware/firmware_export.hpp"
#include "tunekit/firmware/firmware_limits.hpp"
#include "tunekit/firmware/gcode_advance.hpp"
#include "tunekit/firmware/orca_profile.hpp"
#include "tunekit/machine/machine_profile.hpp"

namespace tunekit::calibration {
namespace {

// Plausibility caps of what export writes, whatever the firmware would accept (the firmware's
// own bounds are checked by firmware::validate_settings). A value beyond them is a typing or
// unit error (a value in ms given as s, a fit that ran away), never a printer's setting.
// Advance K, s: 10 is Marlin's upper bound on M900 K (Marlin, Marlin/src/gcode/feature/advance/M900.cpp);
// a liquefier with a 10 s lag could not print at all.
constexpr double kPlausibleMaxAdvanceK_s = 10;
// Smoothing time, s: one second is five times Klipper's own maximum pressure_advance_smooth_time.
constexpr double kPlausibleMaxSmoothing_s = 1;
// Shaper frequency, Hz: below 1 Hz a shaper delays every move by more than half a second (its
// duration is about 0.5/f to 1.5/f); above 1000 Hz is beyond RepRapFirmware's own limit and any frame resonance.
constexpr double kPlausibleMinShaperFreq_hz = 1;
constexpr double kPlausibleMaxShaperFreq_hz = 1000;
// Design flow, mm^3/s: ten times what the fastest high-flow hot ends melt.
constexpr double kPlausibleMaxDesignFlow_mm3_s = 1000;
// Design flow, mm^3/s: a 0.1 mm wide, 0.1 mm thick line at 1 mm/s, slower than any printing
// move; below it the advance design extrapolates to an absurd K and the message would blame K.
constexpr double kPlausibleMinDesignFlow_mm3_s = 0.01;

/// Refuses non-finite and implausible values (exit 2) before anything is computed from them.
void check_plausible(const firmware::CompensatorSettings& s) {
  if (s.pa_k_s && !(*s.pa_k_s >= 0 && *s.pa_k_s <= kPlausibleMaxAdvanceK_s))
    throw InputError(
        fmt::format("advance K {} s is not plausible (accepted: 0 to {} s)", *s.pa_k_s, kPlausibleMaxAdvanceK_s));
  if (s.pa_smooth_s && !(*s.pa_smooth_s >= 0 && *s.pa_smooth_s <= kPlausibleMaxSmoothing_s))
    throw InputError(fmt::format("smoothing time {} s is not plausible (accepted: 0 to {} s)", *s.pa_smooth_s,
                                 kPlausibleMaxSmoothing_s));
  for (const auto& [axis, sh] : s.shapers) {
    if (!(sh.freq_hz >= kPlausibleMinShaperFreq_hz && sh.freq_hz <= kPlausibleMaxShaperFreq_hz))
      throw InputError(fmt::format("{} shaper frequency {} Hz is not plausible (accepted: {} to {} Hz)", axis,
                                   sh.freq_hz, kPlausibleMinShaperFreq_hz, kPlausibleMaxShaperFreq_hz));
    if (!(sh.damping >= 0 && sh.damping < 1))
      throw InputError(
          fmt::format("{} shaper damping ratio {} is not plausible (accepted: 0 to below 1)", axis, sh.damping));
  }
}

/// The options a user gives instead of results, checked before any design uses them.
void check_given_options(const ExportOptions& a) {
  firmware::CompensatorSettings given;
  if (std::isfinite(a.pa_k)) given.pa_k_s = a.pa_k;
  if (std::isfinite(a.pa_smooth)) given.pa_smooth_s = a.pa_smooth;
  check_plausible(given);
  if (std::isfinite(a.design_flow) &&
      !(a.design_flow >= kPlausibleMinDesignFlow_mm3_s && a.design_flow <= kPlausibleMaxDesignFlow_mm3_s))
    throw InputError(fmt::format("--design-flow {} mm^3/s is not plausible (accepted: {} to {} mm^3/s)", a.design_flow,
                                 kPlausibleMinDesignFlow_mm3_s, kPlausibleMaxDesignFlow_mm3_s));
}

/// A Marlin build with FT_MOTION has FT_MOTION's shapers (firmware_limits.hpp).
bool marlin_ft_motion(const ExportOptions& a, firmware::ExportFirmware fw) {
  if (fw != firmware::ExportFirmware::marlin) return false;
  if (a.marlin_ft_live) return true;
  std::error_code ec;
  // A missing file is named by the export that reads it next; anything else is refused here.
  return std::filesystem::exists(a.config, ec) &&
         firmware::marlin_ft_motion_enabled(firmware::read_config_file(a.config));
}

/// The note that replaces a changed line's trailing comment: what set it, from which results, when.
std::string change_note(const ExportOptions& a, const DesignInputs& d) {
  std::string from;
  for (const auto& origin : d.origins)
    from += (from.empty() ? "" : ", ") + std::filesystem::path(origin).filename().string();
  if (std::isfinite(a.pa_k) || !a.shaper_x.empty() || !a.shaper_y.empty() || !a.shaper_z.empty())
    from += from.empty() ? "the command line" : " and the command line";
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  ::gmtime_r(&now, &tm);
  char day[16];
  std::strftime(day, sizeof day, "%Y-%m-%d", &tm);
  // File names reach the configuration's comments (RepRapFirmware's config.g is G-code): comment-safe.
  return fmt::format("set by tunekit export from {} on {}", from.empty() ? "its defaults" : core::comment_safe(from),
                     day);
}

// Klipper reads its extruders from the sections [extruder], [extruder1], [extruder2] ...
// up to extruder98 (Kevin O'Connor et al., Klipper, klippy/kinematics/extruder.py,
// add_printer_objects: `for i in range(99)`); an extruder number beyond is no printer's. The
// same bound serves Marlin's ADVANCE_K entry and RepRapFirmware's drive (M572 D).
constexpr long long kMaxExtruderNumber = 98;

/// `name` for a message: control characters (a newline would break the message) as '?'.
std::string shown(const std::string& name) {
  std::string out = name;
  for (char& c : out)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7F) c = '?';
  return out;
}

bool all_digits(const std::string& s) { return !s.empty() && s.find_first_not_of("0123456789") == std::string::npos; }

/// The extruder number N of "N" or "extruderN" (0 for "extruder"); nullopt for another name.
std::optional<long long> extruder_number(const std::string& e) {
  const std::string prefix = "extruder";
  const std::string digits = e.rfind(prefix, 0) == 0 ? e.substr(prefix.size()) : e;
  if (digits.empty() && e == prefix) return 0;
  if (!all_digits(digits) || (digits != e && digits.front() == '0')) return std::nullopt;
  if (digits.size() > 2) return kMaxExtruderNumber + 1;  // beyond the range, whatever its size
  return std::stoll(digits);
}

/// Refuses an --extruder that is no Klipper extruder section and a --drive out of range (exit 2).
long long checked_extruder(const ExportOptions& a) {
  const auto n = extruder_number(a.extruder);
  if (!n)
    throw InputError(
        fmt::format("--extruder '{}' is not an extruder: give a number 0 to {}, or Klipper's section "
                    "name extruder or extruder1 to extruder{} (klippy/kinematics/extruder.py)",
                    shown(a.extruder), kMaxExtruderNumber, kMaxExtruderNumber));
  if (*n > kMaxExtruderNumber || (a.extruder != "extruder" && a.extruder != "0" && *n == 0))
    throw InputError(
        fmt::format("--extruder '{}' is out of range: extruders are numbered 0 to {} (extruder, "
                    "extruder1 to extruder{})",
                    shown(a.extruder), kMaxExtruderNumber, kMaxExtruderNumber));
  if (a.drive < 0 || a.drive > kMaxExtruderNumber)
    throw InputError(
        fmt::format("--drive {} is out of range: RepRapFirmware's extruder drives (M572 D) are "
                    "numbered 0 to {}",
                    a.drive, kMaxExtruderNumber));
  return *n;
}

/// The letters of the running Marlin's M493 (--marlin-m493-form; default the 2024-2025 form;
/// "none", which calibrate passes for a report that did not show its form, warns and uses them).
firmware::M493Syntax marlin_m493_syntax(const ExportOptions& a) {
  if (a.marlin_m493_form.empty()) return {};
  if (!a.marlin_ft_live)
    throw InputError("--marlin-m493-form needs --marlin-ft-motion (a printer running fixed-time motion)");
  try {
    return firmware::parse_m493_syntax(a.marlin_m493_form);
  } catch (const InputError&) {
    throw InputError(
        fmt::format("--marlin-m493-form '{}' is not one of mode, axis_slash, axis_named, axis_list, "
                    "axis_list_v2",
                    shown(a.marlin_m493_form)));
  }
}

/// Where the settings go: Klipper's section, Marlin's extruder entry, RepRapFirmware's drive.
/// --extruder N (a number) or extruderN: Klipper's [extruder] / [extruderN], Marlin's ADVANCE_K
/// entry N (M900 T), RepRapFirmware's drive N unless --drive is given.
void set_extruder(const ExportOptions& a, firmware::ExportFirmware fw, firmware::CompensatorSettings& settings) {
  const int n = static_cast<int>(checked_extruder(a));
  settings.marlin_ft_motion_live = fw == firmware::ExportFirmware::marlin && a.marlin_ft_live;
  settings.marlin_m493 = marlin_m493_syntax(a);
  settings.extruder_index = n;
  settings.klipper_extruder = n == 0 ? "extruder" : fmt::format("extruder{}", n);
  settings.rrf_drive = a.drive_given ? a.drive : n;
}

/// The files export reads, as the options name them.
std::vector<std::string> option_inputs(const ExportOptions& a) {
  std::vector<std::string> in = a.results;
  for (const std::string* p : {&a.config, &a.profile, &a.orca_in, &a.sliced_in}) in.push_back(*p);
  return in;
}

/// Refuses an output that is one of `inputs` (exit 2): it would replace the file export reads.
void check_outputs(const ExportOptions& a, const std::string& json_file, const std::vector<std::string>& inputs) {
  check_output_not_input(a.gcode_out, "--gcode", inputs);
  check_output_not_input(a.orca_out, "--orca-out", inputs);
  check_output_not_input(a.sliced_out, "--gcode-out", inputs);
  check_output_not_input(a.plot_out, "--plot", inputs);
  check_output_not_input(json_file, "--json-file", inputs);
}

/// The shapers and smoothing the options set or keep, then the check that something is set.
void finish_settings(const ExportOptions& a, const DesignInputs& d,
                     std::map<std::string, firmware::ShaperSetting> shapers, ExportOutcome& outcome) {
  firmware::CompensatorSettings& settings = outcome.settings;
  if ((!a.orca_out.empty() || !a.sliced_out.empty()) && !outcome.design)
    throw InputError("--orca-out and --gcode-out need an advance design: give the results of 'tunekit step' or --pa-k");
  if (!a.sliced_in.empty() != !a.sliced_out.empty()) throw InputError("--gcode-in and --gcode-out go together");
  if (std::isfinite(a.pa_smooth)) {
    if (a.no_pa) throw InputError("--pa-smooth and --no-pa contradict each other");
    settings.pa_smooth_s = a.pa_smooth;
  }
  if (!a.no_shaper) {
    if (!a.shaper_x.empty()) shapers["x"] = parse_shaper_arg(a.shaper_x, "x");
    if (!a.shaper_y.empty()) shapers["y"] = parse_shaper_arg(a.shaper_y, "y");
    if (!a.shaper_z.empty()) shapers["z"] = parse_shaper_arg(a.shaper_z, "z");
    settings.shapers = shapers;
  }
  if (!settings.pa_k_s && !settings.pa_smooth_s && settings.shapers.empty() && !settings.thermal) {
    if (!d.unnamed_axes.empty()) throw InputError("nothing to export; " + d.unnamed_axes.front());
    if (d.rheo && !a.no_pa)
      throw InputError(
          "the rheology prediction gives how tau changes with the flow (relative_tau, 1 at its reference flow), not "
          "tau itself: give it beside the results of 'tunekit step' or 'freq' (export step.json rheo.json), which "
          "size the advance, or set the advance with --pa-k",
          d.rheo->origin);
    throw InputError(
        "nothing to export: give results of 'tunekit step', 'freq', 'shaper' or 'thermal', or --pa-k / --shaper-x / "
        "--thermal-model");
  }
  check_plausible(settings);
}

nlohmann::json export_options_json(const ExportOptions& a, firmware::ExportFirmware fw) {
  return {{"firmware", firmware::to_string(fw)},
          {"config", a.config},
          {"profile", a.profile},
          {"pa_k_s", std::isfinite(a.pa_k) ? nlohmann::json(a.pa_k) : nlohmann::json(nullptr)},
          {"pa_smooth_s", std::isfinite(a.pa_smooth) ? nlohmann::json(a.pa_smooth) : nlohmann::json(nullptr)},
          {"design_flow_mm3_s", std::isfinite(a.design_flow) ? nlohmann::json(a.design_flow) : nlohmann::json(nullptr)},
          {"shaper_x", a.shaper_x},
          {"shaper_y", a.shaper_y},
          {"shaper_z", a.shaper_z},
          {"no_pa", a.no_pa},
          {"no_shaper", a.no_shaper},
          {"thermal_model", a.thermal_model},
          {"no_thermal", a.no_thermal},
          {"heater", a.heater},
          {"kalico_pid", a.kalico_pid},
          {"thermal_loop_delay_s", a.thermal_loop_delay},
          {"write", a.write}};
}

nlohmann::json settings_json(const firmware::CompensatorSettings& settings, firmware::ExportFirmware fw,
                             bool ft_motion) {
  nlohmann::json sj = nlohmann::json::object();
  sj["pa_k_s"] = settings.pa_k_s ? nlohmann::json(*settings.pa_k_s) : nlohmann::json(nullptr);
  sj["pa_smooth_s"] = settings.pa_smooth_s ? nlohmann::json(*settings.pa_smooth_s) : nlohmann::json(nullptr);
  sj["shapers"] = nlohmann::json::object();
  for (const auto& [axis, sh] : settings.shapers)
    sj["shapers"][axis] = {{"type", firmware::canonical_shaper_type(sh.type)},
                           {"firmware_type", firmware::firmware_shaper_name(fw, sh.type, ft_motion)},
                           {"freq_hz", sh.freq_hz},
                           {"damping", sh.damping}};
  if (settings.marlin_ft_motion_live) sj["marlin_m493_form"] = firmware::to_string(settings.marlin_m493);
  return sj;
}

/// --orca-out: the flow-dependent advance as an OrcaSlicer filament profile (merged into --orca-in).
void prepare_orca_profile(const ExportOptions& a, const export_design::LiquefierInputs& li, ExportOutcome& outcome) {
  const auto& flow = outcome.flow;
  firmware::OrcaAdvanceProfile op;
  op.fallback_k_s = *outcome.settings.pa_k_s;
  if (flow) {
    for (const auto& o : flow->orca) op.table.push_back(o);
  } else {
    const double acc = std::isfinite(li.in.print_accel_mm_s2) ? li.in.print_accel_mm_s2 : 0.0;
    for (const auto& s : outcome.design->schedule) op.table.push_back({s.k_s, s.flow_mm3_s, acc});
  }
  if (op.table.size() < 2)
    throw InputError("--orca-out needs a flow-dependent advance: results of 'tunekit step' with two or more levels");
  auto& res = outcome.envelope.results();
  std::string text;
  if (!a.orca_in.empty()) {
    const std::string base = read_file_bytes(a.orca_in);
    outcome.envelope.add_input(a.orca_in, base);
    const auto m = firmware::merge_orca_filament_profile(base, op, a.orca_in);
    text = m.text;
    res["orca"] = {
        {"profile", a.orca_out}, {"merged_from", a.orca_in}, {"changed", m.changed_keys}, {"added", m.added_keys}};
  } else {
    text = firmware::new_orca_filament_profile(op, a.orca_name, "");
    res["orca"] = {{"profile", a.orca_out}, {"merged_from", nullptr}};
  }
  res["orca"]["adaptive_pressure_advance_model"] = firmware::orca_model_text(op.table);
  outcome.files.add(a.orca_out, text);
}

/// --gcode-in/--gcode-out: the sliced G-code with the advance each feature's flow needs.
/// The filament's cross-section is the machine profile's when --profile is given (else the sliced
/// file's "; filament_diameter = D" line).
void prepare_sliced_gcode(const ExportOptions& a, const export_design::LiquefierInputs& li, ExportOutcome& outcome) {
  const auto& flow = outcome.flow;
  const auto& design = outcome.design;
  firmware::GcodeAdvanceOptions go;
  go.firmware = outcome.firmware;
  if (!a.profile.empty()) go.filament_area_mm2 = li.in.filament_area_mm2;
  go.hysteresis = a.hysteresis;
  go.klipper_extruder = outcome.settings.klipper_extruder;
  go.rrf_drive = outcome.settings.rrf_drive;
  if (flow) {
    for (const auto& c : flow->curve) go.k_of_flow.emplace_back(c.flow_mm3_s, c.k_need_s);
  } else {
    for (const auto& s : design->schedule) go.k_of_flow.emplace_back(s.flow_mm3_s, s.k_s);
    if (go.k_of_flow.empty()) go.k_of_flow.emplace_back(design->design_flow_mm3_s, *outcome.settings.pa_k_s);
  }
  const std::string sliced = read_file_bytes(a.sliced_in);
  outcome.envelope.add_input(a.sliced_in, sliced);
  const auto g = firmware::apply_gcode_advance(sliced, go, a.sliced_in);
  nlohmann::json ch = nlohmann::json::array();
  for (const auto& c : g.changes)
    ch.push_back({{"line", c.line}, {"feature", c.feature}, {"flow_mm3_s", c.flow_mm3_s}, {"K_s", c.k_s}});
  outcome.envelope.results()["gcode_post"] = {{"in", a.sliced_in},
                                              {"out", a.sliced_out},
                                              {"features", g.features},
                                              {"hysteresis", a.hysteresis},
                                              {"changes", ch}};
  outcome.files.add(a.sliced_out, g.text);
}

/// Names the temporary files a killed writer of the configuration had left (now removed).
void warn_stale_temporaries(const std::vector<std::string>& removed, CliContext& ctx) {
  for (const auto& t : removed)
    ctx.err << "tunekit: warning: removed " << t
            << ", a temporary file left by a configuration write that was interrupted\n";
}

/// Everything that will be written is computed first (configuration, backup, G-code, profiles);
/// commit_export() then writes all of it together or none of it (core::FileBatch).
void prepare_files(const ExportOptions& a, const export_design::LiquefierInputs& li, ExportOutcome& outcome) {
  const auto& result = outcome.change;
  if (a.write && result.changed()) {
    outcome.backup = firmware::backup_path_for(a.config);
    outcome.envelope.results()["written"] = true;
    outcome.files.add(outcome.backup, result.original, a.config);          // the backup keeps the original's mode
    outcome.files.add(a.config, result.updated, {}, core::Links::follow);  // a configuration: links followed
  }
  if (!a.gcode_out.empty()) outcome.files.add(a.gcode_out, result.gcode);
  if (!a.orca_out.empty()) prepare_orca_profile(a, li, outcome);
  if (!a.sliced_out.empty()) prepare_sliced_gcode(a, li, outcome);
}

/// The results of the envelope: settings, design, agreement, flow design, the change.
void fill_results(const ExportOptions& a, const export_design::LiquefierInputs& li, bool ft_motion,
                  const nlohmann::json& rheology, ExportOutcome& outcome) {
  auto& res = outcome.envelope.results();
  const auto& flow = outcome.flow;
  const auto& design = outcome.design;
  res["settings"] = settings_json(outcome.settings, outcome.firmware, ft_motion);
  if (outcome.pa_k_ci95) res["pa_k_ci95"] = {outcome.pa_k_ci95->first, outcome.pa_k_ci95->second};
  res["design"] = design ? design->to_json() : nlohmann::json(nullptr);
  if (!li.agreement.empty()) res["agreement"] = li.agreement;
  res["flow_advance"] = flow ? flow->to_json() : nlohmann::json(nullptr);
  if (flow && !rheology.is_null()) res["flow_advance"]["rheology"] = rheology;
  if (!a.plot_out.empty()) {
    if (!flow)
      throw InputError("--plot needs a flow-dependent advance: results of 'tunekit step' with two or more levels");
    FlowAdvancePlot plot = flow_advance_plot(*flow);
    if (rheology.is_object()) plot.rheology = flow_rheology_from_json(rheology);
    render_figure(flow_advance_figure(plot), a.plot_out);
  }
  if (outcome.settings.thermal)
    res["thermal"] = export_thermal::thermal_results_json(outcome.firmware, *outcome.settings.thermal);
  res["export"] = outcome.change.to_json();
  outcome.schedule_gcode =
      design ? firmware::advance_schedule_gcode(outcome.firmware, design->schedule, outcome.settings) : std::string();
  res["schedule_gcode"] = outcome.schedule_gcode;
  res["written"] = false;
}

}  // namespace

ExportOutcome compute_export(const ExportOptions& a) { return compute_export(a, read_design_inputs(a.results)); }

ExportOutcome compute_export(const ExportOptions& a, const DesignInputs& inputs) {
  ExportOutcome outcome;
  outcome.options = a;
  const auto fw = firmware::parse_export_firmware(a.firmware);
  outcome.firmware = fw;
  check_given_options(a);
  check_outputs(a, "", option_inputs(a));
  Envelope& env = outcome.envelope;
  for (const auto& d : inputs.files) add_input(env, d);
  for (const auto& w : inputs.warnings) env.warn(w);
  const bool ft_motion = marlin_ft_motion(a, fw);
  auto shapers = export_design::firmware_shapers(inputs, fw, ft_motion, env);
  auto li = export_design::liquefier_inputs(a, inputs, env);
  export_design::apply_machine_profile(a, li, env);
  set_extruder(a, fw, outcome.settings);
  outcome.settings.change_note = change_note(a, inputs);
  outcome.settings.thermal = export_thermal::thermal_settings(a, inputs);
  const nlohmann::json rheology = export_design::design_advance(a, li, outcome);
  outcome.pa_k_ci95 = export_design::advance_interval(li, outcome);
  finish_settings(a, inputs, std::move(shapers), outcome);

  outcome.change = firmware::export_config_file(fw, a.config, outcome.settings);
  env.add_input(a.config, outcome.change.original);
  for (const auto& w : outcome.change.warnings) env.warn(w);
  env.set_options(export_options_json(a, fw));
  fill_results(a, li, ft_motion, rheology, outcome);
  prepare_files(a, li, outcome);
  return outcome;
}

void print_text(const ExportOutcome& o, std::ostream& os) { os << o.change.diff; }

std::string configuration_status(const ExportOutcome& o) {
  if (!o.change.changed()) return fmt::format("{} already has these settings; nothing to change", o.options.config);
  if (o.options.write) return fmt::format("wrote {} (backup: {})", o.options.config, o.backup);
  return "preview only; add --write to apply (a timestamped backup is kept)";
}

int commit_export(const ExportOutcome& o, const OutputOptions& output, CliContext& ctx) {
  const ExportOptions& a = o.options;
  const auto& result = o.change;
  const auto& design = o.design;
  const auto& flow = o.flow;
  const auto& settings = o.settings;
  const auto& env = o.envelope;
  const std::string& schedule = o.schedule_gcode;
  core::FileBatch batch = o.files;
  std::vector<std::string> inputs = option_inputs(a);
  for (const auto& p : env.input_paths()) inputs.push_back(p);
  check_outputs(a, output.output_path, inputs);
  const Emission emission = prepare_emission(env, output);
  const bool output_is_device = !output.output_path.empty() && is_special_output(output.output_path);
  if (!output.output_path.empty() && !output_is_device) batch.add(output.output_path, emission.text);
  {
    // Writers of one configuration take turns (file_lock.hpp): compare and replace under the lock.
    std::optional<core::FileLock> lock;
    if (a.write && result.changed()) {
      lock.emplace(a.config);
      warn_stale_temporaries(lock->remove_stale_temporaries(), ctx);
    }
    // Refuse to overwrite a file that changed since it was read.
    if (a.write && result.changed() && read_file_bytes(a.config) != result.original)
      throw InputError("the configuration file changed since it was read; run the export again", a.config);
    batch.commit();
  }
  if (output_is_device) write_output_text(output.output_path, emission.text);  // -o /dev/stdout: nothing to undo

  if (!output.json) {
    print_text(o, ctx.out);
    if (design)
      ctx.err << fmt::format(
          "tunekit: advance K = {:.4g} s{} ({}) at {:.3g} mm^3/s{}\n", design->k_s,
          o.pa_k_ci95 ? fmt::format(" {} (95 %)", display_interval(o.pa_k_ci95->first, o.pa_k_ci95->second))
                      : std::string(),
          design->k_source, design->design_flow_mm3_s,
          settings.pa_smooth_s ? fmt::format(", smoothing {:.4g} s", *settings.pa_smooth_s) : std::string());
    if (flow) {
      // No band (the single K is off the need even at the design flow): said so, not "nan to nan".
      if (std::isfinite(flow->k_within_lo_mm3_s) && std::isfinite(flow->k_within_hi_mm3_s))
        ctx.err << fmt::format(
            "tunekit: the single K stays within 10 % of the need from {:.3g} to {:.3g} mm^3/s "
            "(identified {:.3g}-{:.3g} mm^3/s)\n",
            flow->k_within_lo_mm3_s, flow->k_within_hi_mm3_s, flow->flow_min_mm3_s, flow->flow_max_mm3_s);
      else
        ctx.err << fmt::format(
            "tunekit: the single K, designed for {:.3g} mm^3/s, is more than 10 % from the need at {:.3g} mm^3/s, "
            "the identified flow nearest to it: no band of flows keeps it within 10 % (identified {:.3g}-{:.3g} "
            "mm^3/s)\n",
            flow->design_flow_mm3_s, std::clamp(flow->design_flow_mm3_s, flow->flow_min_mm3_s, flow->flow_max_mm3_s),
            flow->flow_min_mm3_s, flow->flow_max_mm3_s);
      ctx.err << fmt::format(
          "tunekit: Kalico {}: linear_advance {:.4g} s, nonlinear_offset {:.4g} mm, "
          "linearization_velocity {:.4g} mm/s (within {:.1f} % of the need)\n",
          design::to_string(flow->kalico.model), flow->kalico.linear_advance_s, flow->kalico.nonlinear_offset_mm,
          flow->kalico.linearization_velocity_mm_s, 100 * flow->kalico.max_rel_error);
    }
    // The design's notes say what it means (nothing to act on): informational lines, not warnings.
    if (design)
      for (const auto& n : design->notes) ctx.err << "tunekit: note: " << n << "\n";
    ctx.err << "tunekit: " << configuration_status(o) << "\n";
    if (!result.gcode.empty()) ctx.err << "tunekit: the same settings as G-code:\n" << result.gcode;
    for (const auto& n : result.notes) ctx.err << "tunekit: " << n << "\n";
    if (!schedule.empty() && design && design->schedule.size() >= 2)
      ctx.err << "tunekit: flow-dependent advance (for per-feature G-code; the firmware takes one number):\n"
              << schedule;
  }
  return finish_emission(env, output, emission, ctx, /*write_output_file=*/false);
}

}  // namespace tunekit::calibration
