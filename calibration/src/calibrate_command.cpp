// tunekit calibrate: the technician's one command. It checks every experiment against the
// machine profile before anything is sent, runs them (liquefier flow sweep: feed steps up and
// down through flow levels of the hot end's range; liquefier chirp;
// axis sweeps of X and Y), identifies the models with the functions behind the commands a user
// would run by hand (compute_step, compute_freq, compute_shaper on the CSV files the run wrote;
// their typed outcomes), designs pressure advance and input shaping (compute_export), previews
// the firmware configuration change, and writes a run directory:
//   RUN_DIR/results.json     the envelope: every identified value, compensators, summary
//   RUN_DIR/plotdata.json    the series behind the report's plots
//   RUN_DIR/report.html      one self-contained page (rebuild with `tunekit report RUN_DIR`)
//   RUN_DIR/<experiment>/    each experiment's journal, raw CSV data and (sim) truth.json
//   RUN_DIR/analysis/*.json  each analysis command's own JSON
//   RUN_DIR/config/          the configuration before and after, and the diff
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

#include <unistd.h>

#include <fmt/format.h>

#include "calibrate_liquefier.hpp"
#include "tunekit/calibration/calibrate_command.hpp"
#include "calibrate_plotdata.hpp"
#include "tunekit/calibration/agreement.hpp"
#include "tunekit/calibration/envelope.hpp"
#include "tunekit/calibration/export_command.hpp"
#include "tunekit/calibration/freq_command.hpp"
#include "tunekit/calibration/results_json.hpp"
#include "tunekit/calibration/shaper_command.hpp"
#include "tunekit/calibration/step_command.hpp"
#include "tunekit/calibration/history_record.hpp"
#include "tunekit/calibration/progress.hpp"
#include "tunekit/calibration/report.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/fitting/first_order.hpp"
#include "tunekit/ident/csv.hpp"
#include "tunekit/ident/input_shaper.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/protocols/chirp_plan.hpp"
#include "tunekit/firmware/firmware_export.hpp"
#include "tunekit/protocols/runner.hpp"

#ifndef TUNEKIT_DATASETS_DIR
#define TUNEKIT_DATASETS_DIR "datasets"
#endif

namespace tunekit::calibration {
namespace {

namespace fs = std::filesystem;

struct Experiment {
  std::string name;      // sub-directory and label
  std::string protocol;  // protocols::protocol_specs() name
  std::string axis;
  std::map<std::string, double> params;  // protocol parameter overrides
};

// Runs an analysis as a user's command would (the same compute function), keeping its message and
// exit code but saying which analysis failed.
template <class Fn>
auto calibrate_analysis(const char* command, Fn&& compute) {
  try {
    return compute();
  } catch (const Error& e) {
    std::string msg = e.formatted();
    const std::string prefix = "tunekit: error: ";
    if (msg.rfind(prefix, 0) == 0) msg = msg.substr(prefix.size());
    const std::string what = fmt::format("'tunekit {}' failed: {}", command, msg);
    if (e.code() == ExitCode::fit_failed) throw FitError(what);
    throw InputError(what);
  }
}

// Writes an analysis' JSON envelope where the run keeps it (RUN_DIR/analysis/NAME.json, the file the
// command's --json-file would write) and returns the document as written.
template <class Outcome>
nlohmann::json keep_analysis(const Outcome& outcome, const std::string& json_path, CliContext& ctx) {
  if (ctx.verbosity > 0) print_text(outcome, ctx.err);
  const std::string text = prepare_emission(to_envelope(outcome), OutputOptions{}).text;
  write_output_text(json_path, text);
  return nlohmann::json::parse(text);
}

// An estimate for the agreement check from a fitted parameter with its 95 % interval; false when
// it has none or it is not finite.
bool calibrate_estimate(const fitting::Param& p, const std::string& method, Estimate& out) {
  out = {method, p.value, p.ci95_lo, p.ci95_hi};
  return std::isfinite(out.value) && std::isfinite(out.ci95_lo) && std::isfinite(out.ci95_hi);
}

// Paths inside the run directory are written relative to it, so that results.json does not
// depend on where the run lives (and two runs of one machine are byte-identical).
void strip_prefix(nlohmann::json& j, const std::string& prefix) {
  if (j.is_string()) {
    std::string s = j.get<std::string>();
    for (std::size_t pos; (pos = s.find(prefix)) != std::string::npos;) s.erase(pos, prefix.size());
    j = s;
  } else if (j.is_structured()) {
    for (auto& v : j) strip_prefix(v, prefix);
  }
}

std::string utc_stamp() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y%m%d-%H%M%S", &tm);
  return buf;
}

}  // namespace

int run_calibrate(const CalibrateArgs& a, CliContext& ctx) {
  const bool sim = a.machine == "sim";
  if (!sim && a.profile.empty())
    throw InputError(
        "a real machine needs its profile: --profile FILE (limits and sensors; see datasets/machines/sim.toml)");
  const std::string profile_path =
      !a.profile.empty() ? a.profile : std::string(TUNEKIT_DATASETS_DIR) + "/machines/sim.toml";
  const auto profile = !a.profile.empty() ? machine::load_machine_profile(a.profile) : protocols::builtin_sim_profile();

  std::vector<Experiment> exps;
  const bool camera_path =
      !a.skip_liquefier && choose_liquefier_path(a.liquefier, profile, profile_path) == LiquefierPath::camera;
  // Off a terminal the photo source must be known before anything is printed.
  const bool can_prompt = ::isatty(STDIN_FILENO) != 0 && ctx.interactive;
  if (camera_path) check_photo_source(a.camera, sim, can_prompt);
  if (!a.skip_liquefier && !camera_path) {
    // The step test is a flow sweep: every level reached from below and from above, so that tau,
    // K and theta are known per arrival level (the liquefier's dynamics change with the flow).
    exps.push_back({"liquefier-step", "liquefier-flow-sweep", "", {}});
    exps.push_back({"liquefier-chirp", "liquefier-chirp", "", {}});
  }
  if (camera_path)
    for (const auto& t : camera_tests()) exps.push_back({t.name, t.protocol, "", t.params});
  if (!a.skip_axes) {
    if (!profile.sensors.accelerometer)
      throw InputError("the axis sweeps need an accelerometer ([sensors] accelerometer = true)", profile_path);
    exps.push_back({"axis-x", "axis-sweep", "x", {}});
    exps.push_back({"axis-y", "axis-sweep", "y", {}});
  }
  if (exps.empty()) throw InputError("nothing to calibrate: both --skip-liquefier and --skip-axes were given");
  OutputOptions output = a.output;
  prepare_record(output, profile.id);  // --record: a bad machine id or database fails before the machine moves

  // Each calibration keeps its own run directory: a used one is never written into again.
  std::string run_dir = a.out_dir;
  if (run_dir.empty()) {
    const std::string base = "runs/calibrate-" + utc_stamp();
    run_dir = base;
    for (int k = 2; fs::exists(run_dir); ++k) run_dir = base + "-" + std::to_string(k);
  } else if (fs::exists(run_dir) && !(fs::is_directory(run_dir) && fs::is_empty(run_dir))) {
    throw InputError("the run directory already exists; give a new --out (or leave it out for runs/calibrate-UTCSTAMP)",
                     run_dir);
  }
  fs::create_directories(run_dir + "/analysis");
  fs::create_directories(run_dir + "/config");

  // The chirp is sized from the expected liquefier corner: the literature time constant until
  // the step test has measured one (it runs first).
  protocols::ChirpPlan chirp_plan = protocols::plan_liquefier_chirp(protocols::kLiteratureLiquefierTau_s);
  std::string chirp_basis = fmt::format("the literature time constant {} s", display_number(chirp_plan.expected_tau_s));
  // The simulated camera photographs everything the simulated printer prints.
  auto bed = camera_path && a.camera.camera == "sim" ? std::make_shared<sim::SimPrintBed>() : nullptr;
  auto options_for = [&](const Experiment& e, bool dry) {
    protocols::RunOptions o;
    o.protocol = e.protocol;
    o.params = e.params;
    if (sim) o.sim_bed = bed;
    o.axis = e.axis.empty() ? "x" : e.axis;
    o.machine = sim ? "sim" : a.profile;
    o.port = a.port;
    o.sim_options = a.sim_options;
    // The simulated printer runs the firmware being calibrated (its planner rules and dialect).
    if (sim && std::none_of(o.sim_options.begin(), o.sim_options.end(),
                            [](const std::string& s) { return s.rfind("firmware=", 0) == 0; })) {
      // Kalico is a Klipper fork: its G-code, API server and planner are Klipper's.
      const auto fw = firmware::parse_export_firmware(a.firmware);
      o.sim_options.push_back(
          "firmware=" + (fw == firmware::ExportFirmware::kalico ? std::string("klipper") : firmware::to_string(fw)));
    }
    o.dry_run = dry;
    o.run_dir = run_dir + "/" + e.name;
    o.file_tag = "tunekit";  // raw_data_x_tunekit.csv: names that do not change from run to run
    if (e.protocol == "liquefier-chirp") {
      o.params["expected_tau_s"] = chirp_plan.expected_tau_s;
      // Staircase steps as long as the chirp's end allows (10 per period, at most 50 ms): Klipper
      // stops after every extrude-only move, so fewer, longer moves keep the delivered feed close
      // to the recorded staircase.
      o.params["segment_s"] = std::min(0.05, 1.0 / (10 * chirp_plan.freq_max_hz));
      // ... and as short a stop as the extruder allows: its own acceleration limit.
      if (profile.extruder.max_accel_mm_s2 > 0) o.params["accel_mm_s2"] = profile.extruder.max_accel_mm_s2;
    }
    return o;
  };

  // Safety first: every protocol is built and checked against the limits before any byte is sent.
  for (const auto& e : exps) (void)protocols::run_experiment(options_for(e, true));

  ProgressBar bar(ctx, static_cast<int>(exps.size()) + 3);
  std::map<std::string, protocols::RunResult> runs;
  nlohmann::json step_analysis;
  std::optional<StepOutcome> step_outcome;
  for (const auto& e : exps) {
    if (e.name == "liquefier-chirp" && step_outcome && step_outcome->analysis.pooled) {
      const double tau = step_outcome->analysis.pooled->value("tau_s");
      if (std::isfinite(tau) && tau > 0) {
        chirp_plan = protocols::plan_liquefier_chirp(tau);
        chirp_basis = fmt::format("the step test's time constant {} s", display_number(tau));
      }
    }
    auto o = options_for(e, false);
    const double est = protocols::run_experiment(options_for(e, true)).experiment.estimated_duration_s;
    bar.begin("run " + e.name, sim ? std::max(1.0, est / 4) : est);
    runs[e.name] = protocols::run_experiment(o);
    bar.end(runs[e.name].status);
    if (e.name == "liquefier-step") {  // identified at once: it sizes the chirp
      const std::string csv = runs[e.name].files.at("load_cell");
      // The analysis `tunekit step` makes of this log with its defaults: the same steps and
      // operating points (the levels the steps arrive at), which export designs from.
      StepOptions so;
      so.file = csv;
      so.time_column = "time";
      so.input_column = "feed";
      so.output_column = "force";
      step_outcome = calibrate_analysis("step", [&] { return compute_step(so); });
      step_analysis = keep_analysis(*step_outcome, run_dir + "/analysis/step.json", ctx);
    }
  }

  Envelope env("calibrate");
  // Inputs are recorded relative to the run directory: the run can move, and two runs of the
  // same machine give byte-identical results.json files.
  auto add_input = [&](const std::string& path) {
    env.add_input(fs::relative(path, run_dir).generic_string(), ident::read_file_bytes(path));
  };
  env.set_options({{"machine", a.machine},
                   {"profile", a.profile.empty() ? "builtin" : a.profile},
                   {"firmware", a.firmware},
                   {"config", a.config},
                   {"write", a.write},
                   {"sim", a.sim_options}});
  nlohmann::json& res = env.results();
  nlohmann::json plot = nlohmann::json::object();
  res["machine"] = profile.name;
  nlohmann::json summary = nlohmann::json::array();
  nlohmann::json agreement = nlohmann::json::array();
  nlohmann::json notes = nlohmann::json::array();
  // A summary row: the value at `path`, its 95 % interval at `ci_path` or, without one, its basis.
  auto row = [&](const std::string& label, const std::string& path, const std::string& unit, const std::string& ci_path,
                 const std::string& basis = "") {
    nlohmann::json r{{"label", label}, {"path", path}, {"unit", unit}};
    if (!ci_path.empty()) r["ci_path"] = ci_path;
    else r["basis"] = basis;
    summary.push_back(r);
  };
  std::vector<std::string> export_inputs;
  std::optional<fitting::Param> step_tau;  // the liquefier's tau from the step analysis, for the agreement

  bar.begin("identify models", 3);
  if (camera_path) {
    auto cam = analyze_camera_prints(run_dir, a.camera, profile, runs, bed, can_prompt, ctx);
    const std::string out = run_dir + "/analysis/step.json";
    StepOptions so;
    so.file = cam.width_csv;
    so.time_column = "time";
    so.input_column = "setpoint_width";
    so.output_column = "width";
    so.analysis.model = fitting::StepModel::fopdt;
    const auto width_steps = calibrate_analysis("step", [&] { return compute_step(so); });
    const auto j = keep_analysis(width_steps, out, ctx);
    add_input(cam.width_csv);
    add_input(cam.photo);
    res["liquefier"]["step"] = j.at("results");
    const auto& pooled = width_steps.analysis.pooled;
    if (pooled) step_tau = pooled->param("tau_s");
    add_ring_prediction(cam.results, pooled ? pooled->value("K") : std::nan(""),
                        pooled ? pooled->value("tau_s") : std::nan(""),
                        pooled ? pooled->value("theta_s") : std::nan(""));
    res["liquefier"]["camera"] = cam.results;
    plot["step"] = step_plotdata(cam.width_csv, width_steps.analysis, "setpoint_width", "width", "set-point width (mm)",
                                 "width (mm)");
    plot["linewidth"] = cam.linewidth_plot;
    export_inputs.push_back(out);
    summary.push_back({{"label", "liquefier time constant tau (line widths)"},
                       {"path", "liquefier.step.pooled.params.tau_s.value"},
                       {"unit", "s"}});
    summary.push_back(
        {{"label", "tau standard error"}, {"path", "liquefier.step.pooled.params.tau_s.stderr"}, {"unit", "s"}});
    summary.push_back({{"label", "liquefier dead time theta"},
                       {"path", "liquefier.step.pooled.params.theta_s.value"},
                       {"unit", "s"}});
    summary.push_back({{"label", "width gain K"}, {"path", "liquefier.step.pooled.params.K.value"}, {"unit", "1"}});
    if (cam.results.contains("ring")) {
      summary.push_back({{"label", "ring frequency"}, {"path", "liquefier.camera.ring.freq_hz"}, {"unit", "Hz"}});
      summary.push_back({{"label", "ring gain (measured)"}, {"path", "liquefier.camera.ring.gain"}, {"unit", "1"}});
      summary.push_back(
          {{"label", "ring phase (measured)"}, {"path", "liquefier.camera.ring.phase_deg"}, {"unit", "deg"}});
      if (cam.results["ring"].contains("model_phase_deg")) {
        summary.push_back(
            {{"label", "ring phase (step model)"}, {"path", "liquefier.camera.ring.model_phase_deg"}, {"unit", "deg"}});
        summary.push_back({{"label", "dead time from the ring's phase"},
                           {"path", "liquefier.camera.ring.theta_from_phase_s"},
                           {"unit", "s"}});
      }
    }
    for (const auto& w : cam.results["warnings"]) env.warn(w.get<std::string>());
  }
  if (runs.count("liquefier-step")) {
    const auto& r = runs["liquefier-step"];
    const std::string csv = r.files.at("load_cell");
    const std::string out = run_dir + "/analysis/step.json";
    const auto& j = step_analysis;
    add_input(csv);
    res["liquefier"]["step"] = j.at("results");
    plot["step"] = step_plotdata(csv, step_outcome->analysis);
    if (step_outcome->analysis.pooled) step_tau = step_outcome->analysis.pooled->param("tau_s");
    export_inputs.push_back(out);
    const double area = profile.filament_area_mm2();
    std::vector<std::string> level_text;
    for (auto& l : res["liquefier"]["step"]["operating_points"]) {
      l["flow_mm3_s"] = l.at("u").get<double>() * area;
      if (l.at("n_rising").get<int>() > 0 && l.at("n_falling").get<int>() > 0)
        level_text.push_back(fmt::format("{} mm^3/s: {} s", display_number(l["flow_mm3_s"].get<double>()),
                                         display_number(l.at("tau_s").get<double>())));
    }
    if (!level_text.empty()) {
      std::string joined;
      for (const auto& t : level_text) joined += (joined.empty() ? "" : "; ") + t;
      std::string trend;
      if (const auto& tau_trend = step_outcome->analysis.level_trends.tau)
        trend = fmt::format(" (tau = a u^b, b = {})", display_number(tau_trend->value("b")));
      notes.push_back(fmt::format("flow sweep: tau at each level reached from both sides, {}{}", joined, trend));
    }
    const std::string p = "liquefier.step.pooled.params.";
    row("liquefier time constant tau (step response)", p + "tau_s.value", "s", p + "tau_s.ci95");
    row("liquefier dead time theta (step response)", p + "theta_s.value", "s", p + "theta_s.ci95");
    row("liquefier gain K (step response)", p + "K.value", "N/(mm/s)", p + "K.ci95");
  }
  if (runs.count("liquefier-chirp")) {
    const auto& r = runs["liquefier-chirp"];
    const std::string csv = r.files.at("load_cell");
    const std::string out = run_dir + "/analysis/freq.json";
    // Analysed as a user would analyse the file: `tunekit freq FILE --input feed --output force`
    // sizes the analysis from the record itself (where the chirp starts, the band it excites).
    FreqOptions fo;
    fo.file = csv;
    fo.time_column = "time";
    fo.input_column = "feed";
    fo.output_column = "force";
    const auto chirp = calibrate_analysis("freq", [&] { return compute_freq(fo); });
    const auto j = keep_analysis(chirp, out, ctx);
    add_input(csv);
    res["liquefier"]["freq"] = j.at("results");
    res["liquefier"]["chirp_plan"] = {{"expected_tau_s", chirp_plan.expected_tau_s},
                                      {"basis", chirp_basis},
                                      {"corner_hz", chirp_plan.corner_hz},
                                      {"freq_min_hz", chirp_plan.freq_min_hz},
                                      {"freq_max_hz", chirp_plan.freq_max_hz},
                                      {"duration_s", chirp_plan.duration_s},
                                      {"settle_s", chirp_plan.settle_s}};
    plot["bode"] = bode_plotdata(j.at("results"));
    const auto& bb = *chirp.broadband;
    const fitting::FitResult* fit = chirp.reported_fit();
    if (fit != nullptr) {
      const std::string p = "liquefier.freq.fit.params.";
      row(fmt::format("tau from the frequency response (chirp, {})",
                      j.at("results").at("fit").at("method").get<std::string>()),
          p + "tau_s.value", "s", p + "tau_s.ci95");
    }
    notes.push_back(
        fmt::format("chirp sized from {}: corner {} Hz, {}-{} Hz over {} s; analysed from {} s up to {} Hz in Welch "
                    "segments of {} samples ({} Hz bins)",
                    chirp_basis, display_number(chirp_plan.corner_hz), display_number(chirp_plan.freq_min_hz),
                    display_number(chirp_plan.freq_max_hz), display_number(chirp_plan.duration_s),
                    display_number(bb.start_s), display_number(bb.fmax_hz), bb.segment_length,
                    display_number(bb.sample_rate_hz / static_cast<double>(bb.segment_length))));
    Estimate by_step, by_freq;
    if (step_tau && fit != nullptr && calibrate_estimate(*step_tau, "step response", by_step) &&
        calibrate_estimate(fit->param("tau_s"), "frequency response", by_freq)) {
      auto a = compare_estimates("liquefier time constant tau", "s", by_step, by_freq);
      a["id"] = "tau";
      if (!a.at("agree").get<bool>()) env.warn(a.at("statement").get<std::string>());
      agreement.push_back(a);
    }
  }
  for (const char* axis : {"x", "y"}) {
    const std::string name = std::string("axis-") + axis;
    if (!runs.count(name)) continue;
    const std::string csv = runs[name].files.at("accel");
    const std::string out = run_dir + "/analysis/shaper_" + axis + ".json";
    // The recommendation is made among the target firmware's shapers (and its damping bounds).
    ShaperOptions so;
    so.accel.files = {csv};
    so.accel.input.axis = axis[0];
    so.firmware = firmware::parse_export_firmware(a.firmware);
    const auto j = keep_analysis(calibrate_analysis("shaper", [&] { return compute_shaper(so); }), out, ctx);
    add_input(csv);
    res["axes"][axis] = j.at("results").at("axes").at(axis);
    plot[std::string("psd_") + axis] = psd_plotdata(res["axes"][axis]);
    export_inputs.push_back(out);
    const std::string base = std::string("axes.") + axis;
    row(fmt::format("{} resonance frequency", axis), base + ".modes[0].freq_hz", "Hz", base + ".modes[0].freq_ci95");
    row(fmt::format("{} damping ratio", axis), base + ".modes[0].zeta", "1", base + ".modes[0].zeta_ci95");
    row(fmt::format("{} shaper frequency", axis), base + ".recommended.freq_hz", "Hz", "", "designed");
    row(fmt::format("{} max acceleration", axis), base + ".recommended.max_accel_mm_s2", "mm/s^2", "", "designed");
  }
  bar.end("models identified");

  // Compensators and the configuration change (preview unless --write).
  bar.begin("design compensators", 1);
  std::string config = a.config;
  if (config.empty()) {
    const std::map<std::string, std::string> examples{
        {"klipper", "printer.cfg"}, {"kalico", "printer.cfg"}, {"marlin", "Configuration_adv.h"}, {"rrf", "config.g"}};
    const auto it = examples.find(a.firmware);
    if (it == examples.end()) throw InputError("--firmware must be klipper, kalico, marlin or rrf");
    config = run_dir + "/config/" + it->second;
    fs::copy_file(std::string(TUNEKIT_DATASETS_DIR) + "/firmware/" + it->second, config,
                  fs::copy_options::overwrite_existing);
  }
  ExportOptions eo;
  eo.firmware = a.firmware;
  eo.config = config;
  eo.profile = profile_path;
  eo.results = export_inputs;
  // A Marlin printer that answered M493 with fixed-time motion enabled bypasses M593/M900 U:
  // its settings go to M493 (runner.cpp reads the report into each run's summary).
  const bool ft_live = std::any_of(runs.begin(), runs.end(), [](const auto& kv) {
    static const nlohmann::json::json_pointer ft_motion("/firmware/ft_motion");
    const auto& summary = kv.second.summary;
    return summary.contains(ft_motion) && summary.at(ft_motion) == "active";
  });
  if (ft_live && firmware::parse_export_firmware(a.firmware) == firmware::ExportFirmware::marlin) {
    eo.marlin_ft_live = true;
    res["firmware_ft_motion"] = "active (M493): settings written as M493";
  }
  eo.write = a.write;
  const auto exported = calibrate_analysis("export", [&] { return compute_export(eo); });
  {
    OutputOptions keep;
    keep.json = true;  // the summary lines go to the verbose stream only
    keep.output_path = run_dir + "/analysis/export.json";
    std::ostringstream quiet_out, quiet_err;
    CliContext quiet{quiet_out, quiet_err};
    calibrate_analysis("export", [&] { return commit_export(exported, keep, quiet); });
    if (ctx.verbosity > 0) print_text(exported, ctx.err);
  }
  const auto ex = read_results_json(run_dir + "/analysis/export.json");
  res["compensators"] = ex.at("results");
  // The report draws the advance the liquefier needs against flow (the export's flow design).
  if (exported.flow) plot["flow_advance"] = res["compensators"]["flow_advance"];
  const std::string diff = exported.change.diff;
  res["config_diff"] = diff;
  core::write_file_atomic(run_dir + "/config/changes.diff", diff);
  if (exported.settings.pa_k_s)
    row("pressure advance K", "compensators.settings.pa_k_s", "s", "", "designed (K = tau)");
  if (exported.settings.pa_smooth_s)
    row("advance smoothing time", "compensators.settings.pa_smooth_s", "s", "", "designed");
  bar.end(diff.empty() ? "configuration already up to date" : "configuration diff ready");
  res["summary"] = summary;
  res["agreement"] = agreement;
  if (exported.design)
    for (const auto& n : exported.design->notes) notes.push_back(n);
  res["notes"] = notes;
  for (const auto& w : ex.value("warnings", std::vector<std::string>{})) {
    nlohmann::json wj = w;
    strip_prefix(wj, run_dir + "/");
    env.warn(wj.get<std::string>());
  }

  strip_prefix(res, run_dir + "/");
  bar.begin("write report", 2);
  core::write_file_atomic(run_dir + "/results.json", env.dump());
  core::write_file_atomic(run_dir + "/plotdata.json", plot.dump() + "\n");
  const std::string report = write_report(run_dir);
  bar.end(report);

  if (!a.output.json) {
    if (!diff.empty()) ctx.out << diff << (diff.back() == '\n' ? "" : "\n");
    ctx.out << fmt::format("report: {}\n", report);
  }
  output.record_source = run_dir;
  return emit(env, output, ctx);
}

}  // namespace tunekit::calibration
