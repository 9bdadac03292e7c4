// tunekit export: design pressure/linear advance and input shaping from the JSON results of
// `tunekit step`, `freq`, `shaper` and `rheo` (or values on the command line) and write them
// into a Klipper printer.cfg, a Marlin Configuration_adv.h or a RepRapFirmware config.g.
// By default only a unified diff is printed; --write applies it (backup + atomic rename).
// The command line (options, help) is in cmd_export_options.cpp.
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

#include "tunekit/calibration/envelope.hpp"
#include "tunekit/calibration/export_command.hpp"
#include "tunekit/calibration/json_access.hpp"
#include "tunekit/calibration/plots.hpp"
#include "tunekit/calibration/results_json.hpp"
#include "tunekit/calibration/agreement.hpp"
#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/ident/csv.hpp"
#include "tunekit/ident/flow_advance.hpp"
#include "tunekit/ident/pressure_advance.hpp"
#include "tunekit/core/atomic_file.hpp"
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

double number_at(const nlohmann::json& j, const std::string& what, const std::string& path) {
  if (j.is_null()) return fitting::kNaN;
  if (!j.is_number()) throw InputError(fmt::format("{} must be a number", what), path);
  return j.get<double>();
}

}  // namespace

ExportOutcome compute_export(const ExportOptions& a) {
  ExportOutcome outcome;
  outcome.options = a;
  const auto fw = firmware::parse_export_firmware(a.firmware);
  outcome.firmware = fw;
  {
    firmware::CompensatorSettings given;  // the options alone, checked before any design uses them
    if (std::isfinite(a.pa_k)) given.pa_k_s = a.pa_k;
    if (std::isfinite(a.pa_smooth)) given.pa_smooth_s = a.pa_smooth;
    check_plausible(given);
  }
  if (std::isfinite(a.design_flow) && !(a.design_flow > 0 && a.design_flow <= kPlausibleMaxDesignFlow_mm3_s))
    throw InputError(fmt::format("--design-flow {} mm^3/s is not plausible (accepted: above 0 to {} mm^3/s)",
                                 a.design_flow, kPlausibleMaxDesignFlow_mm3_s));
  Envelope& env = outcome.envelope;
  ident::AdvanceInputs in;
  double freq_tau = fitting::kNaN, freq_tau_stderr = fitting::kNaN;
  // tau as each analysis reports it ({value, stderr, ci95}), for the agreement of the two.
  nlohmann::json step_tau_param, freq_tau_param;
  nlohmann::json agreement = nlohmann::json::array();
  std::map<std::string, firmware::ShaperSetting> shapers;
  std::vector<std::string> sources;
  // Operating points whose u is a volumetric flow (mm^3/s): converted to filament feed once the
  // filament area is known.
  std::vector<bool> point_is_flow;
  std::vector<std::string> unnamed_axes;          // shaper results under a file stem instead of an axis
  std::optional<ident::TauPowerLaw> trend_tau_u;  // tau = a u^b over the operating points' u
  std::vector<ident::FlowTau> levels;             // results.operating_points (u or flow)
  std::vector<bool> level_is_flow;
  bool points_are_flow = false;

  // A Marlin build with FT_MOTION has FT_MOTION's shapers (firmware_limits.hpp).
  bool ft_motion = false;
  if (fw == firmware::ExportFirmware::marlin) {
    std::ifstream cfg_in(a.config, std::ios::binary);
    std::stringstream cfg_text;
    cfg_text << cfg_in.rdbuf();
    ft_motion = (cfg_in && firmware::marlin_ft_motion_enabled(cfg_text.str())) || a.marlin_ft_live;
  }
  std::string reading;  // the results file being read, for errors deep inside it
  try {
    for (const auto& path : a.results) {
      reading = path;
      std::string bytes;
      const nlohmann::json j = read_results_json(path, &bytes);
      env.add_input(path, bytes);
      const std::string cmd = j.value("command", std::string());
      const auto& res = value_at_or_null(j, "/results"_json_pointer);
      if (!res.is_object()) throw InputError("no 'results' object: not a tunekit results file", path);
      sources.push_back(cmd);
      if (cmd == "step") {
        const auto& params = value_at_or_null(res, "/pooled/params"_json_pointer);
        if (params.is_object()) {
          in.tau_s =
              number_at(value_at_or_null(params, "/tau_s/value"_json_pointer), "pooled.params.tau_s.value", path);
          step_tau_param = value_at_or_null(params, "/tau_s"_json_pointer);
          in.tau_stderr_s =
              number_at(value_at_or_null(params, "/tau_s/stderr"_json_pointer), "pooled.params.tau_s.stderr", path);
          in.theta_s =
              number_at(value_at_or_null(params, "/theta_s/value"_json_pointer), "pooled.params.theta_s.value", path);
          in.gain = number_at(value_at_or_null(params, "/K/value"_json_pointer), "pooled.params.K.value", path);
          if (const auto& unit = value_at_or_null(params, "/K/unit"_json_pointer); unit.is_string())
            in.gain_unit = unit.get<std::string>();
          in.tau_source = "step";
        }
        // Power-law trend of tau over u (the operating points' input), and per-point 95 %
        // intervals (results.operating_points[].tau_ci95). An operating point is the level the
        // steps arrive at; one at u = 0 (arrivals at a stop) has no flow to design for.
        const auto& ta = value_at_or_null(res, "/trend/tau_s/a"_json_pointer);
        const auto& tb = value_at_or_null(res, "/trend/tau_s/b"_json_pointer);
        if (ta.is_number() && tb.is_number()) trend_tau_u = ident::TauPowerLaw{ta.get<double>(), tb.get<double>()};
        const auto& ops = value_at_or_null(res, "/operating_points"_json_pointer);
        const auto& u_unit = value_at_or_null(res, "/units/input"_json_pointer);
        const bool flow_points = u_unit.is_string() && ident::is_volumetric_flow_unit(u_unit.get<std::string>());
        points_are_flow = flow_points;
        if (ops.is_array())
          for (const auto& op : ops) {
            ident::LiquefierPoint p;
            p.feed_mm_s = number_at(value_at_or_null(op, "/u"_json_pointer), "operating_points[].u", path);
            if (!(p.feed_mm_s > 0)) continue;
            point_is_flow.push_back(flow_points);
            p.gain = number_at(value_at_or_null(op, "/K"_json_pointer), "operating_points[].K", path);
            p.tau_s = number_at(value_at_or_null(op, "/tau_s"_json_pointer), "operating_points[].tau_s", path);
            p.theta_s = number_at(value_at_or_null(op, "/theta_s"_json_pointer), "operating_points[].theta_s", path);
            in.points.push_back(p);
            ident::FlowTau ft;
            ft.flow_mm3_s =
                number_at(value_at_or_null(op, "/flow_mm3_s"_json_pointer), "operating_points[].flow_mm3_s", path);
            level_is_flow.push_back(std::isfinite(ft.flow_mm3_s));
            if (!level_is_flow.back()) ft.flow_mm3_s = p.feed_mm_s;
            ft.tau_s = p.tau_s;
            const auto& ci = value_at_or_null(op, "/tau_ci95"_json_pointer);
            if (ci.is_array() && ci.size() == 2) {
              ft.tau_lo_s = number_at(ci[0], "operating_points[].tau_ci95[0]", path);
              ft.tau_hi_s = number_at(ci[1], "operating_points[].tau_ci95[1]", path);
            }
            levels.push_back(ft);
          }
      } else if (cmd == "freq") {
        // The fit freq reports as its result (results.fit), as its report and the history do.
        freq_tau_param = value_at_or_null(res, "/fit/params/tau_s"_json_pointer);
        freq_tau =
            number_at(value_at_or_null(res, "/fit/params/tau_s/value"_json_pointer), "fit.params.tau_s.value", path);
        freq_tau_stderr =
            number_at(value_at_or_null(res, "/fit/params/tau_s/stderr"_json_pointer), "fit.params.tau_s.stderr", path);
      } else if (cmd == "shaper") {
        const auto& axes = value_at_or_null(res, "/axes"_json_pointer);
        if (!axes.is_object()) throw InputError("shaper results without 'axes'", path);
        for (const auto& axis_item : axes.items()) {
          // A plain variable, not a structured binding: the lambdas below capture it (clang 14
          // refuses to capture a structured binding).
          const std::string axis = axis_item.key();
          const auto& v = axis_item.value();
          const auto& rec = value_at_or_null(v, "/recommended"_json_pointer);
          if (!rec.is_object()) continue;
          if (axis != "x" && axis != "y") {
            if (axis == "z")
              env.warn(
                  fmt::format("{}: the {} axis shaper is not exported (firmware shapers cover x and y)", path, axis));
            else {
              unnamed_axes.push_back(
                  fmt::format("{}: the shaper of '{}' is not exported: that record names no axis; run "
                              "'tunekit shaper' on it with --axis x or --axis y",
                              path, axis));
              env.warn(unnamed_axes.back());
            }
            continue;
          }
          auto setting_of = [&](const nlohmann::json& c, const std::string& what) {
            firmware::ShaperSetting s;
            if (!c.contains("type") || !c["type"].is_string())
              throw InputError(fmt::format("axes.{}.{}.type must be a string", axis, what), path);
            s.type = c["type"].get<std::string>();
            s.freq_hz = number_at(value_at_or_null(c, "/freq_hz"_json_pointer), what + ".freq_hz", path);
            const double z = number_at(value_at_or_null(c, "/damping"_json_pointer), what + ".damping", path);
            if (std::isfinite(z)) s.damping = z;
            return s;
          };
          // The firmware must have the shaper and accept its damping (firmware_limits.hpp).
          auto usable = [&](const firmware::ShaperSetting& s) {
            const auto f = firmware::limits::find_shaper(fw, firmware::canonical_shaper_type(s.type), ft_motion);
            return f && s.damping <= f->max_damping;
          };
          firmware::ShaperSetting s = setting_of(rec, "recommended");
          if (!usable(s)) {
            // The overall recommendation is not available on this firmware: the best-scoring
            // candidate the firmware has (the results list every type's best frequency).
            std::optional<firmware::ShaperSetting> best;
            double best_score = 0;
            for (const auto& c : value_at_or_null(v, "/candidates"_json_pointer)) {
              const auto cs = setting_of(c, "candidates[]");
              const double score = number_at(value_at_or_null(c, "/score"_json_pointer), "candidates[].score", path);
              if (!usable(cs) || !std::isfinite(score)) continue;
              if (!best || score < best_score) {
                best = cs;
                best_score = score;
              }
            }
            if (!best)
              throw InputError(
                  fmt::format("axes.{}: the recommended shaper {} is not available in {} and no candidate "
                              "is ({} has {}{}); run 'tunekit shaper --firmware {}'",
                              axis, s.type, firmware::limits::firmware_title(fw), firmware::limits::firmware_title(fw),
                              firmware::limits::shaper_list(fw),
                              fw == firmware::ExportFirmware::marlin ? ": its input shaping is ZV only" : "",
                              firmware::to_string(fw)),
                  path);
            env.warn(
                fmt::format("{}: axis {}: the recommended {} shaper is not available in {} (it has {}); using the "
                            "best-scoring candidate it has: {} at {:.1f} Hz",
                            path, axis, s.type, firmware::limits::firmware_title(fw), firmware::limits::shaper_list(fw),
                            best->type, best->freq_hz));
            s = *best;
          }
          shapers[axis] = s;
        }
      } else if (cmd == "rheo") {
        const auto& pred = value_at_or_null(res, "/prediction"_json_pointer);
        if (!pred.is_object()) throw InputError("rheo results without 'prediction'", path);
        try {
          in.rheo_flow_mm3_s = pred.at("flow_mm3_s").get<std::vector<double>>();
          in.rheo_relative_tau = pred.at("relative_tau").get<std::vector<double>>();
        } catch (const nlohmann::json::exception&) {
          throw InputError("prediction.flow_mm3_s and prediction.relative_tau must be arrays of numbers", path);
        }
        in.rheo_reference_flow_mm3_s = number_at(value_at_or_null(pred, "/reference_flow_mm3_s"_json_pointer),
                                                 "prediction.reference_flow_mm3_s", path);
      } else {
        throw InputError(fmt::format("results of '{}' cannot be exported (step, freq, shaper or rheo)", cmd), path);
      }
    }
  } catch (const nlohmann::json::exception& e) {
    throw InputError(fmt::format("unexpected content in a results file: {}", e.what()), reading);
  }
  if (!std::isfinite(in.tau_s) && std::isfinite(freq_tau)) {
    in.tau_s = freq_tau;
    in.tau_stderr_s = freq_tau_stderr;
    in.tau_source = "freq";
  } else if (std::isfinite(in.tau_s) && std::isfinite(freq_tau)) {
    // Both measured: the step value is designed with; the two are compared by the one rule
    // (agreement.hpp), as calibrate compares them.
    Estimate by_step, by_freq;
    if (estimate_from_param(&step_tau_param, "step response", by_step) &&
        estimate_from_param(&freq_tau_param, "frequency response", by_freq)) {
      agreement.push_back(compare_estimates("liquefier time constant tau", "s", by_step, by_freq));
      agreement.back()["id"] = "tau";
      if (!agreement.back().at("agree").get<bool>())
        env.warn(agreement.back().at("statement").get<std::string>() + "; the step value is used");
    } else {
      env.warn(
          fmt::format("the step response gives tau = {:.4g} s, the frequency response {:.4g} s; without a 95 % "
                      "interval for each they are not compared; the step value is used",
                      in.tau_s, freq_tau));
    }
  }
  if (std::isfinite(a.pa_k)) {
    in.tau_s = a.pa_k;
    in.tau_stderr_s = fitting::kNaN;
    in.tau_source = "command line";
    in.points.clear();
    in.rheo_flow_mm3_s.clear();
    in.rheo_relative_tau.clear();
  }

  machine::MachineProfile profile;
  if (!a.profile.empty()) {
    profile = machine::load_machine_profile(a.profile);
    env.add_input(a.profile);
  }
  in.filament_area_mm2 = profile.filament_area_mm2();
  for (std::size_t i = 0; i < in.points.size() && i < point_is_flow.size(); ++i)
    if (point_is_flow[i]) in.points[i].feed_mm_s /= in.filament_area_mm2;  // mm^3/s -> mm/s of filament
  in.line_area_mm2 = profile.line_area_mm2();
  in.print_speed_mm_s = profile.print.speed_mm_s;
  in.print_accel_mm_s2 = profile.print.max_accel_mm_s2;
  in.extruder_accel_limit_mm_s2 = profile.extruder.max_accel_mm_s2;
  in.design_flow_mm3_s = a.design_flow;

  firmware::CompensatorSettings& settings = outcome.settings;
  settings.klipper_extruder = a.extruder;
  settings.rrf_drive = a.drive;
  settings.marlin_ft_motion_live = fw == firmware::ExportFirmware::marlin && a.marlin_ft_live;
  // --extruder N (a number): Klipper's [extruder] / [extruderN], Marlin's ADVANCE_K entry N
  // (M900 T), RepRapFirmware's drive N unless --drive is given.
  if (!a.extruder.empty() && a.extruder.find_first_not_of("0123456789") == std::string::npos) {
    const int n = std::stoi(a.extruder);
    settings.extruder_index = n;
    settings.klipper_extruder = n == 0 ? "extruder" : "extruder" + a.extruder;
    if (!a.drive_given) settings.rrf_drive = n;
  }
  {
    // The note that replaces a changed line's trailing comment: what set it, from which results, when.
    std::string from;
    for (const auto& path : a.results)
      from += (from.empty() ? "" : ", ") + std::filesystem::path(path).filename().string();
    if (std::isfinite(a.pa_k) || !a.shaper_x.empty() || !a.shaper_y.empty())
      from += from.empty() ? "the command line" : " and the command line";
    const std::time_t now = std::time(nullptr);
    std::tm tm{};
    ::gmtime_r(&now, &tm);
    char day[16];
    std::strftime(day, sizeof day, "%Y-%m-%d", &tm);
    settings.change_note =
        fmt::format("set by tunekit export from {} on {}", from.empty() ? "its defaults" : from, day);
  }
  std::optional<ident::AdvanceDesign>& design = outcome.design;
  const bool have_tau = std::isfinite(in.tau_s) || !in.points.empty();
  if (!a.no_pa && have_tau) {
    if (a.profile.empty())
      env.warn(
          "no --profile: assuming 1.75 mm filament, a 0.45 x 0.2 mm line at 60 mm/s, and no acceleration limits "
          "(the smoothing time is not designed)");
    design = ident::design_advance(in);
    settings.pa_k_s = design->k_s;
    settings.pa_smooth_s = firmware::smoothing_time_for(fw, *design);
    for (const auto& w : design->warnings) env.warn(w);
  }
  // Flow-dependent design (flow_advance.hpp) when two or more levels were identified.
  std::optional<ident::FlowAdvanceDesign>& flow = outcome.flow;
  nlohmann::json flow_rheology;  // rheology cross-check of tau(Q), when a prediction was given
  if (design && design->schedule.size() >= 2 && design->k_source == "operating points") {
    ident::FlowAdvanceInputs fin;
    fin.filament_area_mm2 = in.filament_area_mm2;
    if (!levels.empty()) {
      for (std::size_t i = 0; i < levels.size(); ++i) {
        auto l = levels[i];
        if (!level_is_flow[i] && !points_are_flow) l.flow_mm3_s *= in.filament_area_mm2;  // feed mm/s -> mm^3/s
        fin.levels.push_back(l);
      }
    } else {
      for (const auto& p : in.points)
        if (std::isfinite(p.feed_mm_s) && std::isfinite(p.tau_s))
          fin.levels.push_back({p.feed_mm_s * in.filament_area_mm2, p.tau_s});
    }
    if (trend_tau_u) {
      // tau = a u^b with u a feed (mm/s): in flow, a (Q/A)^b = (a A^-b) Q^b.
      ident::TauPowerLaw t = *trend_tau_u;
      if (!points_are_flow) t.a *= std::pow(in.filament_area_mm2, -t.b);
      fin.trend = t;
    }
    fin.design_flow_mm3_s = design->design_flow_mm3_s;
    fin.theta_s = design->theta_s;
    if (std::isfinite(in.print_accel_mm_s2) && in.print_accel_mm_s2 > 0) fin.orca_accels_mm_s2 = {in.print_accel_mm_s2};
    flow = ident::design_flow_advance(fin);
    for (const auto& w : flow->warnings) env.warn(w);
    if (in.rheo_flow_mm3_s.size() >= 2 && in.rheo_flow_mm3_s.size() == in.rheo_relative_tau.size()) {
      // Rheology cross-check: the predicted shape of tau(Q), scaled to the measured tau at the
      // prediction's reference flow, against the measured tau(Q) over the identified flows.
      const auto& rq = in.rheo_flow_mm3_s;
      const auto& rr = in.rheo_relative_tau;
      auto rel_at = [&](double q) {
        if (q <= rq.front()) return rr.front();
        if (q >= rq.back()) return rr.back();
        const auto it = std::upper_bound(rq.begin(), rq.end(), q);
        const std::size_t i = static_cast<std::size_t>(it - rq.begin());
        return rr[i - 1] + (q - rq[i - 1]) / (rq[i] - rq[i - 1]) * (rr[i] - rr[i - 1]);
      };
      const double qref =
          std::isfinite(in.rheo_reference_flow_mm3_s) ? in.rheo_reference_flow_mm3_s : flow->design_flow_mm3_s;
      const double scale = ident::flow_tau_s(fin, qref) / rel_at(qref);
      std::vector<double> fq, ft;
      double gap = 0;
      for (const auto& c : flow->curve) {
        fq.push_back(c.flow_mm3_s);
        ft.push_back(scale * rel_at(c.flow_mm3_s));
        gap = std::max(gap, std::abs(ft.back() - c.tau_s) / c.tau_s);
      }
      flow_rheology =
          nlohmann::json{{"flow_mm3_s", fq}, {"tau_pred_s", ft}, {"max_gap_rel", gap}, {"reference_flow_mm3_s", qref}};
      if (gap > 0.2)
        env.warn(
            fmt::format("the rheology prediction of tau(Q) differs from the measured one by up to {:.0f} % over the "
                        "identified flows (scaled to agree at {:.3g} mm^3/s)",
                        100 * gap, qref));
    }
    settings.pa_k_s = flow->k_design_s;
    // One design everywhere: the per-flow schedule and K follow the flow design (which uses the
    // power-law trend when the step analysis gave one).
    design->k_s = flow->k_design_s;
    for (auto& s : design->schedule) s.k_s = ident::needed_advance_s(fin, s.flow_mm3_s);
    if (fw == firmware::ExportFirmware::kalico) {
      firmware::KalicoAdvanceSetting k;
      k.model = ident::to_string(flow->kalico.model);
      k.linear_advance_s = flow->kalico.linear_advance_s;
      k.nonlinear_offset_mm = flow->kalico.nonlinear_offset_mm;
      k.linearization_velocity_mm_s = flow->kalico.linearization_velocity_mm_s;
      if (std::isfinite(flow->kalico_time_offset_s)) k.time_offset_s = flow->kalico_time_offset_s;
      settings.kalico = k;
    }
  }
  if ((!a.orca_out.empty() || !a.sliced_out.empty()) && !design)
    throw InputError("--orca-out and --gcode-out need an advance design: give the results of 'tunekit step' or --pa-k");
  if (!a.sliced_in.empty() != !a.sliced_out.empty()) throw InputError("--gcode-in and --gcode-out go together");
  if (std::isfinite(a.pa_smooth)) {
    if (a.no_pa) throw InputError("--pa-smooth and --no-pa contradict each other");
    settings.pa_smooth_s = a.pa_smooth;
  }
  if (!a.no_shaper) {
    if (!a.shaper_x.empty()) shapers["x"] = parse_shaper_arg(a.shaper_x, "x");
    if (!a.shaper_y.empty()) shapers["y"] = parse_shaper_arg(a.shaper_y, "y");
    settings.shapers = shapers;
  }
  if (!settings.pa_k_s && !settings.pa_smooth_s && settings.shapers.empty()) {
    if (!unnamed_axes.empty()) throw InputError("nothing to export; " + unnamed_axes.front());
    throw InputError("nothing to export: give results of 'tunekit step', 'freq' or 'shaper', or --pa-k / --shaper-x");
  }
  check_plausible(settings);

  outcome.change = firmware::export_config_file(fw, a.config, settings);
  const auto& result = outcome.change;
  env.add_input(a.config, result.original);
  for (const auto& w : result.warnings) env.warn(w);

  env.set_options(
      {{"firmware", firmware::to_string(fw)},
       {"config", a.config},
       {"profile", a.profile},
       {"pa_k_s", std::isfinite(a.pa_k) ? nlohmann::json(a.pa_k) : nlohmann::json(nullptr)},
       {"pa_smooth_s", std::isfinite(a.pa_smooth) ? nlohmann::json(a.pa_smooth) : nlohmann::json(nullptr)},
       {"design_flow_mm3_s", std::isfinite(a.design_flow) ? nlohmann::json(a.design_flow) : nlohmann::json(nullptr)},
       {"shaper_x", a.shaper_x},
       {"shaper_y", a.shaper_y},
       {"no_pa", a.no_pa},
       {"no_shaper", a.no_shaper},
       {"write", a.write}});

  auto& res = env.results();
  nlohmann::json sj = nlohmann::json::object();
  sj["pa_k_s"] = settings.pa_k_s ? nlohmann::json(*settings.pa_k_s) : nlohmann::json(nullptr);
  sj["pa_smooth_s"] = settings.pa_smooth_s ? nlohmann::json(*settings.pa_smooth_s) : nlohmann::json(nullptr);
  sj["shapers"] = nlohmann::json::object();
  for (const auto& [axis, sh] : settings.shapers)
    sj["shapers"][axis] = {{"type", firmware::canonical_shaper_type(sh.type)},
                           {"firmware_type", firmware::firmware_shaper_name(fw, sh.type, ft_motion)},
                           {"freq_hz", sh.freq_hz},
                           {"damping", sh.damping}};
  res["settings"] = sj;
  res["design"] = design ? design->to_json() : nlohmann::json(nullptr);
  if (!agreement.empty()) res["agreement"] = agreement;
  res["flow_advance"] = flow ? flow->to_json() : nlohmann::json(nullptr);
  if (flow && !flow_rheology.is_null()) res["flow_advance"]["rheology"] = flow_rheology;
  if (!a.plot_out.empty()) {
    if (!flow)
      throw InputError("--plot needs a flow-dependent advance: results of 'tunekit step' with two or more levels");
    render_figure(flow_advance_figure(res["flow_advance"]), a.plot_out);
  }
  res["export"] = result.to_json();
  outcome.schedule_gcode = design ? firmware::advance_schedule_gcode(fw, design->schedule, settings) : std::string();
  res["schedule_gcode"] = outcome.schedule_gcode;
  res["written"] = false;

  // Everything that will be written is computed first (configuration, backup, G-code, JSON);
  // then all of it is written together or none of it (core::FileBatch).
  core::FileBatch& batch = outcome.files;
  if (a.write && result.changed()) {
    outcome.backup = firmware::backup_path_for(a.config);
    const std::string& backup = outcome.backup;
    res["written"] = true;
    batch.add(backup, result.original);
    batch.add(a.config, result.updated);
  }
  if (!a.gcode_out.empty()) batch.add(a.gcode_out, result.gcode);
  if (!a.orca_out.empty()) {
    firmware::OrcaAdvanceProfile op;
    op.fallback_k_s = *settings.pa_k_s;
    if (flow) {
      for (const auto& o : flow->orca) op.table.push_back(o);
    } else {
      const double acc = std::isfinite(in.print_accel_mm_s2) ? in.print_accel_mm_s2 : 0.0;
      for (const auto& s : design->schedule) op.table.push_back({s.k_s, s.flow_mm3_s, acc});
    }
    if (op.table.size() < 2)
      throw InputError("--orca-out needs a flow-dependent advance: results of 'tunekit step' with two or more levels");
    std::string text;
    if (!a.orca_in.empty()) {
      const std::string base = ident::read_file_bytes(a.orca_in);
      env.add_input(a.orca_in, base);
      const auto m = firmware::merge_orca_filament_profile(base, op, a.orca_in);
      text = m.text;
      res["orca"] = {
          {"profile", a.orca_out}, {"merged_from", a.orca_in}, {"changed", m.changed_keys}, {"added", m.added_keys}};
    } else {
      text = firmware::new_orca_filament_profile(op, a.orca_name, "");
      res["orca"] = {{"profile", a.orca_out}, {"merged_from", nullptr}};
    }
    res["orca"]["adaptive_pressure_advance_model"] = firmware::orca_model_text(op.table);
    batch.add(a.orca_out, text);
  }
  if (!a.sliced_out.empty()) {
    firmware::GcodeAdvanceOptions go;
    go.firmware = fw;
    go.hysteresis = a.hysteresis;
    go.klipper_extruder = settings.klipper_extruder;
    go.rrf_drive = settings.rrf_drive;
    if (flow) {
      for (const auto& c : flow->curve) go.k_of_flow.emplace_back(c.flow_mm3_s, c.k_need_s);
    } else {
      for (const auto& s : design->schedule) go.k_of_flow.emplace_back(s.flow_mm3_s, s.k_s);
      if (go.k_of_flow.empty()) go.k_of_flow.emplace_back(design->design_flow_mm3_s, *settings.pa_k_s);
    }
    const std::string sliced = ident::read_file_bytes(a.sliced_in);
    env.add_input(a.sliced_in, sliced);
    const auto g = firmware::apply_gcode_advance(sliced, go, a.sliced_in);
    nlohmann::json ch = nlohmann::json::array();
    for (const auto& c : g.changes)
      ch.push_back({{"line", c.line}, {"feature", c.feature}, {"flow_mm3_s", c.flow_mm3_s}, {"K_s", c.k_s}});
    res["gcode_post"] = {{"in", a.sliced_in},
                         {"out", a.sliced_out},
                         {"features", g.features},
                         {"hysteresis", a.hysteresis},
                         {"changes", ch}};
    batch.add(a.sliced_out, g.text);
  }
  return outcome;
}

void print_text(const ExportOutcome& o, std::ostream& os) { os << o.change.diff; }

int commit_export(const ExportOutcome& o, const OutputOptions& output, CliContext& ctx) {
  const ExportOptions& a = o.options;
  const auto& result = o.change;
  const auto& design = o.design;
  const auto& flow = o.flow;
  const auto& settings = o.settings;
  const auto& env = o.envelope;
  const std::string& schedule = o.schedule_gcode;
  const std::string& backup = o.backup;
  core::FileBatch batch = o.files;
  // Refuse to overwrite a file that changed since it was read.
  if (a.write && result.changed() && ident::read_file_bytes(a.config) != result.original)
    throw InputError("the configuration file changed since it was read; run the export again", a.config);
  const Emission emission = prepare_emission(env, output);
  const bool output_is_device = !output.output_path.empty() && is_special_output(output.output_path);
  if (!output.output_path.empty() && !output_is_device) batch.add(output.output_path, emission.text);
  batch.commit();
  if (output_is_device) write_output_text(output.output_path, emission.text);  // -o /dev/stdout: nothing to undo

  if (!output.json) {
    print_text(o, ctx.out);
    if (design)
      ctx.err << fmt::format(
          "tunekit: advance K = {:.4g} s ({}) at {:.3g} mm^3/s{}\n", design->k_s, design->k_source,
          design->design_flow_mm3_s,
          settings.pa_smooth_s ? fmt::format(", smoothing {:.4g} s", *settings.pa_smooth_s) : std::string());
    if (flow) {
      ctx.err << fmt::format(
          "tunekit: the single K stays within 10 % of the need from {:.3g} to {:.3g} mm^3/s "
          "(identified {:.3g}-{:.3g} mm^3/s)\n",
          flow->k_within_lo_mm3_s, flow->k_within_hi_mm3_s, flow->flow_min_mm3_s, flow->flow_max_mm3_s);
      ctx.err << fmt::format(
          "tunekit: Kalico {}: linear_advance {:.4g} s, nonlinear_offset {:.4g} mm, "
          "linearization_velocity {:.4g} mm/s (within {:.1f} % of the need)\n",
          ident::to_string(flow->kalico.model), flow->kalico.linear_advance_s, flow->kalico.nonlinear_offset_mm,
          flow->kalico.linearization_velocity_mm_s, 100 * flow->kalico.max_rel_error);
    }
    // The design's notes say what it means (nothing to act on): informational lines, not warnings.
    if (design)
      for (const auto& n : design->notes) ctx.err << "tunekit: note: " << n << "\n";
    if (!result.changed())
      ctx.err << fmt::format("tunekit: {} already has these settings; nothing to change\n", a.config);
    else if (a.write) ctx.err << fmt::format("tunekit: wrote {} (backup: {})\n", a.config, backup);
    else ctx.err << "tunekit: preview only; add --write to apply (a timestamped backup is kept)\n";
    if (!result.gcode.empty()) ctx.err << "tunekit: the same settings as G-code:\n" << result.gcode;
    for (const auto& n : result.notes) ctx.err << "tunekit: " << n << "\n";
    if (!schedule.empty() && design && design->schedule.size() >= 2)
      ctx.err << "tunekit: flow-dependent advance (for per-feature G-code; the firmware takes one number):\n"
              << schedule;
  }
  return finish_emission(env, output, emission, ctx, /*write_output_file=*/false);
}

}  // namespace tunekit::calibration
