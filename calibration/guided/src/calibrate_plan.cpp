// tunekit calibrate, stage 1: the plan. The experiments for the profile and the liquefier path,
// a fresh run directory, and every protocol checked against the machine's limits before any
// byte is sent.
#include <algorithm>
#include <ctime>
#include <cmath>
#include <filesystem>

#include <fmt/format.h>

#include "calibrate_liquefier.hpp"
#include "calibrate_stages.hpp"
#include "tunekit/calibration/results/history_record.hpp"
#include "tunekit/calibration/presentation/report.hpp"
#include "tunekit/calibration/results/results_json.hpp"
#include "tunekit/calibration/analyses/simulated_machine.hpp"
#include "tunekit/core/input_read_scope.hpp"
#include "tunekit/core/text.hpp"
#include "tunekit/firmware/firmware_export.hpp"
#include "tunekit/protocols/experiment_design.hpp"
#include "tunekit/machine/profile_import.hpp"
#include "tunekit/sim/builtin_profile.hpp"
#include "tunekit/sim/sim_camera.hpp"
#include "tunekit/sim/simulator.hpp"

#ifndef TUNEKIT_DATASETS_DIR
#define TUNEKIT_DATASETS_DIR "datasets"
#endif

namespace tunekit::calibration {
namespace {

namespace fs = std::filesystem;

std::string utc_stamp() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y%m%d-%H%M%S", &tm);
  return buf;
}

std::vector<PlannedExperiment> choose_experiments(const CalibrateArgs& a, const CalibrationProfile& p,
                                                  bool camera_path) {
  std::vector<PlannedExperiment> exps;
  // The thermal experiment first: its record starts with the hot end at rest.
  if (a.thermal) exps.push_back({"heater", "heater-identify", "", {}, "", 0, {}, {}, {}});
  if (!a.skip_liquefier && !camera_path) {
    // The step test is a flow sweep: every level reached from below and from above, so that tau,
    // K and theta are known per arrival level (the liquefier's dynamics change with the flow).
    exps.push_back({"liquefier-step", "liquefier-flow-sweep", "", {}, "", 0, {}, {}, {}});
    exps.push_back({"liquefier-chirp", "liquefier-chirp", "", {}, "", 0, {}, {}, {}});
  }
  if (camera_path)
    for (const auto& t : camera_tests(p.profile)) exps.push_back({t.name, t.protocol, "", t.params, "", 0, {}, {}, {}});
  if (!a.skip_axes) {
    if (!p.profile.sensors.accelerometer)
      throw InputError("the axis sweeps need an accelerometer ([sensors] accelerometer = true)", p.path);
    // Each axis twice: a coarse pass over the whole band locates the mode, a fine pass sweeps its
    // band (experiment_design.hpp); the axis' analysis is named by the fine pass.
    for (const std::string axis : {"x", "y"}) {
      exps.push_back({"axis-" + axis + "-coarse", "axis-sweep", axis, {}, "axis-" + axis, 0, {}, {}, {}});
      exps.push_back({"axis-" + axis, "axis-sweep", axis, {}, "", 0, {}, {}, {}});
    }
  }
  if (exps.empty())
    throw InputError("nothing to calibrate: both --skip-liquefier and --skip-axes were given (and no --thermal)");
  return exps;
}

/// --param: "EXPERIMENT.NAME=VALUE" or "PROTOCOL.NAME=VALUE", applied to every experiment of that
/// name or protocol (the protocol checks the name and the value with its other parameters).
void apply_params(const std::vector<std::string>& params, std::vector<PlannedExperiment>& exps) {
  for (const auto& text : params) {
    const auto eq = text.find('='), dot = text.find('.');
    if (eq == std::string::npos || dot == std::string::npos || dot > eq)
      throw InputError(fmt::format(
          "--param '{}' is not EXPERIMENT.NAME=VALUE (e.g. axis-x.freq_end_hz=80 or liquefier-chirp.segment_s=0.05)",
          text));
    const std::string who = text.substr(0, dot), name = text.substr(dot + 1, eq - dot - 1);
    const auto value = core::parse_decimal(text.substr(eq + 1));
    if (!value || !std::isfinite(*value))
      throw InputError(fmt::format("--param {}: '{}' is not a finite decimal number", text, text.substr(eq + 1)));
    std::string known;
    bool used = false;
    for (auto& e : exps) {
      known += fmt::format("{}{} ({})", known.empty() ? "" : ", ", e.name, e.protocol);
      if (e.name == who || e.protocol == who) e.params[name] = *value, used = true;
    }
    if (!used)
      throw InputError(fmt::format("--param {}: this calibration has no experiment or protocol '{}' (it has: {})", text,
                                   who, known));
  }
}

// The chirp is designed within the limits checked before anything is sent: its staircase step
// and feed levels come from the machine (the same for any time constant), and the time constant
// it is sized from lies in [kChirpTauMin_s, kChirpTauMax_s] (the step test's, clamped), whose
// extremes are checked too. Below 2 ms the band is the staircase's reach whatever tau is; above
// twice Bellini's 0.45 s (a PEEK-class liquefier's) the chirp would only grow longer.
constexpr double kChirpTauMin_s = 0.002;
constexpr double kChirpTauMax_s = 2 * protocols::kLiteratureLiquefierTau_s;

// The chirp's mean feed (the protocol's nominal 2 mm/s), where the prior's tau sizes the plan's chirp.
constexpr double kChirpMeanFeed_mm_s = 2.0;
// The shortest design a budget may ask for: the sweeps at their fastest rate, the holds at their
// fewest time constants (experiment_design.hpp).
constexpr double kShortestDesignScale = protocols::kFineSweepRate_hz_s / protocols::kMaxSweepRate_hz_s;

// Each calibration keeps its own run directory: a used one is never written into again.
std::string make_run_dir(const std::string& out_dir) {
  std::string run_dir = out_dir;
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
  return run_dir;
}

}  // namespace

std::string bundled_dataset_path(const std::string& relative) {
  return (fs::path(TUNEKIT_DATASETS_DIR) / relative).string();
}

std::string resolved_calibrate_firmware(const std::string& requested, const std::string& profile_firmware) {
  if (!requested.empty()) return firmware::to_string(firmware::parse_export_firmware(requested));
  const std::string fw = core::lower(profile_firmware);
  if (fw == "prusa") return "marlin";
  if (fw == "klipper" || fw == "kalico" || fw == "marlin" || fw == "rrf") return fw;
  return "klipper";
}

double clamped_chirp_tau_s(double tau_s) { return std::clamp(tau_s, kChirpTauMin_s, kChirpTauMax_s); }

CalibrationProfile load_calibration_profile(const CalibrateArgs& a) {
  if (a.machine != "sim" && a.profile.empty())
    throw InputError(
        "a real machine needs its profile: --profile FILE (limits and sensors; see datasets/machines/sim.toml)");
  if (!a.profile.empty()) {
    // The import and the format check read the file once; the import first, so that a file that
    // cannot be read is reported as such, not as a TOML profile given --sensor.
    const core::InputReadScope read_once;
    machine::ProfileImportOptions io;
    io.sensors = a.sensors;
    std::string bytes;
    auto profile = machine::import_machine_profile(a.profile, io, &bytes);
    if (!a.sensors.empty() && !machine::is_firmware_configuration(a.profile))
      throw InputError(
          "--sensor declares sensors a firmware configuration does not list; a TOML profile lists its own "
          "in [sensors]",
          a.profile);
    return {std::move(profile), a.profile, input_digest(a.profile, bytes)};
  }
  // The built-in profile's text is the bundled sim.toml's, byte for byte (built in at compile time).
  const std::string bundled = bundled_dataset_path("machines/sim.toml");
  return {sim::builtin_sim_profile(), bundled, input_digest(bundled, sim::builtin_sim_profile_toml())};
}

namespace {

/// The simulator's options of a calibration on it: --sim, and the firmware being calibrated,
/// which the simulated printer runs (its planner rules and dialect) unless --sim names one.
std::vector<std::string> simulator_options(const CalibrateArgs& a) {
  std::vector<std::string> options = a.sim_options;
  if (std::none_of(options.begin(), options.end(), [](const std::string& s) { return s.rfind("firmware=", 0) == 0; })) {
    // Kalico is a Klipper fork: its G-code, API server and planner are Klipper's.
    const auto fw = firmware::parse_export_firmware(a.firmware);
    options.push_back("firmware=" +
                      (fw == firmware::ExportFirmware::kalico ? std::string("klipper") : firmware::to_string(fw)));
  }
  return options;
}

// A real printer's sensors as the predictions assume them when nothing better is known: an
// ADXL345 read at 3.2 kHz and a hobby load cell (docs/interval-coverage.md, `noisy`).
constexpr double kTypicalAccelNoise_mm_s2 = 200;
constexpr double kTypicalLoadCellNoise_N = 0.2;
constexpr double kTypicalLoadCellRate_hz = 200;

/// The priors the predicted intervals are made with: a desktop printer's typical plant, read by
/// the simulated printer's own sensors (their noise and rates) or by typical ones.
void set_priors(CalibrationPlan& plan, const sim::SimConfig& sim_config) {
  const auto& sensors = plan.profile.profile.sensors;
  plan.liquefier_prior =
      plan.sim ? protocols::typical_liquefier_prior(sim_config.force_noise_N, sim_config.load_cell_rate_hz)
               : protocols::typical_liquefier_prior(kTypicalLoadCellNoise_N, kTypicalLoadCellRate_hz);
  plan.axis_prior = plan.sim ? protocols::typical_axis_prior(sim_config.accel_noise_mm_s2, sim_config.accel_rate_hz)
                             : protocols::typical_axis_prior(kTypicalAccelNoise_mm_s2, sensors.accelerometer_rate_hz);
}

}  // namespace

std::optional<protocols::ExperimentPrediction> predict_experiment(const PlannedExperiment& e,
                                                                  const protocols::Experiment& built,
                                                                  const protocols::LiquefierPrior& liquefier,
                                                                  const protocols::AxisPrior& axis) {
  if (!e.locates.empty()) return std::nullopt;  // a coarse pass: its mode is the fine pass' prior
  if (built.protocol == "axis-sweep") return protocols::predict_axis_sweep(built, axis);
  if (built.protocol == "liquefier-flow-sweep" || built.protocol == "liquefier-chirp")
    return protocols::predict_liquefier_record(built, liquefier);
  return std::nullopt;
}

CalibrationPlan plan_calibration(const CalibrateArgs& given, const CalibrationProfile& profile, bool can_prompt) {
  CalibrationPlan plan;
  plan.options = given;
  // The firmware of the profile given (the built-in simulated printer's calibration is Klipper's).
  plan.options.firmware =
      resolved_calibrate_firmware(given.firmware, given.profile.empty() ? std::string() : profile.profile.firmware);
  const CalibrateArgs& a = plan.options;
  plan.profile = profile;
  plan.sim = a.machine == "sim";
  plan.can_prompt = can_prompt;
  plan.camera_path =
      !a.skip_liquefier && choose_liquefier_path(a.liquefier, profile.profile, profile.path) == LiquefierPath::camera;
  // The simulated printer's own camera is the photo source of its camera path unless another is given.
  auto& cam = plan.options.camera;
  if (plan.camera_path && plan.sim && cam.camera.empty() && cam.photo.empty() && cam.camera_device.empty())
    cam.camera = "sim";
  // Off a terminal the photo source must be known before anything is printed.
  if (plan.camera_path) check_photo_source(cam, plan.sim, can_prompt);
  plan.experiments = choose_experiments(a, profile, plan.camera_path);
  apply_params(a.params, plan.experiments);
  plan.output = a.output;
  if (!a.dry_run) {
    prepare_record(plan.output,
                   profile.profile.id);  // --record: a bad machine id or database fails before the machine moves
    plan.run_dir = make_run_dir(a.out_dir);
  }
  // The simulator's options, read once: the simulated printer of every run, whose prints the
  // simulated camera photographs.
  const sim::SimConfig sim_config = plan.sim ? sim::SimConfig::for_machine(profile.profile, simulator_options(a))
                                             : sim::SimConfig::from_options(a.sim_options);
  if (plan.camera_path && cam.camera == "sim") plan.bed = std::make_shared<sim::SimPrintBed>(sim_config.seed);
  if (plan.sim) plan.simulator = simulated_machine(sim_config, plan.bed);
  set_priors(plan, sim_config);
  check_plan(plan);
  return plan;
}

namespace {

/// The fine pass `fine`'s envelope: the band of its coarse pass as that was built and checked.
std::optional<protocols::FineSweepEnvelope> fine_envelope(const CalibrationPlan& plan, const PlannedExperiment& fine) {
  for (const auto& c : plan.experiments)
    if (c.locates == fine.name && c.checked.params.count("freq_end_hz"))
      return protocols::FineSweepEnvelope{c.checked.params.at("freq_start_hz"), c.checked.params.at("freq_end_hz")};
  return std::nullopt;
}

/// Every experiment built at the plan's design scale and checked against the limits (the chirp
/// also for the extremes of the time constants it may be sized from later, each fine pass for
/// the widest bands at both ends of its coarse pass' band); their machine time.
double build_and_check(CalibrationPlan& plan) {
  double total_s = 0;
  for (auto& e : plan.experiments) {
    const auto built = protocols::run_experiment(experiment_run_options(plan, e, plan.chirp, true)).experiment;
    e.estimated_s = built.estimated_duration_s;
    e.checked = built;
    e.predicted = predict_experiment(e, built, plan.liquefier_prior, plan.axis_prior);
    total_s += e.estimated_s;
    if (e.protocol == "axis-sweep" && e.locates.empty())
      if (const auto envelope = fine_envelope(plan, e))
        for (const auto& mode : protocols::fine_sweep_extremes(*envelope))
          protocols::run_experiment(experiment_run_options(plan, e, plan.chirp, true, &mode));
    if (e.protocol != "liquefier-chirp") continue;
    plan.chirp = protocols::plan_liquefier_chirp(plan.chirp.expected_tau_s, built.params.at("segment_s"));
    for (const double tau : {kChirpTauMin_s, kChirpTauMax_s})
      protocols::run_experiment(experiment_run_options(plan, e, protocols::plan_liquefier_chirp(tau), true));
  }
  return total_s;
}

/// --budget-s: the largest design scale whose plan takes at most the budget (bisection; the
/// plan's machine time rises with the scale). InputError when even the shortest plan exceeds it.
void fit_budget(CalibrationPlan& plan, double budget_s) {
  plan.design_scale = kShortestDesignScale;
  const double shortest = build_and_check(plan);
  if (shortest > budget_s)
    throw InputError(fmt::format(
        "--budget-s {:g}: the shortest plan these experiments allow takes {:.1f} s of machine time (the fine passes "
        "at {:g} Hz/s, holds of {:g} time constants); give at least that, or leave experiments out",
        budget_s, shortest, protocols::kMaxSweepRate_hz_s, protocols::kMinHoldTaus));
  double lo = kShortestDesignScale, hi = 1;
  for (int i = 0; i < 12; ++i) {
    plan.design_scale = 0.5 * (lo + hi);
    (build_and_check(plan) <= budget_s ? lo : hi) = plan.design_scale;
  }
  plan.design_scale = lo;
}

}  // namespace

void check_plan(CalibrationPlan& plan) {
  // The chirp is sized from the expected liquefier corner: the prior's time constant at the
  // chirp's mean feed until the step test has measured one (it runs first).
  const auto& prior = plan.liquefier_prior;
  plan.chirp = protocols::plan_liquefier_chirp(
      clamped_chirp_tau_s(prior.tau_ref_s * std::pow(kChirpMeanFeed_mm_s / prior.ref_feed_mm_s, prior.b)));
  plan.chirp_basis = fmt::format("the prior's time constant {} s", display_number(plan.chirp.expected_tau_s));
  // Safety first: every protocol is built and checked against the limits before any byte is sent.
  plan.design_scale = 1;
  const double total_s = build_and_check(plan);
  const double budget = plan.options.budget_s;
  if (budget > 0 && total_s > budget) {
    // What the budget costs: the predicted intervals of the design without it, kept to compare.
    for (auto& e : plan.experiments) e.unbudgeted = e.predicted;
    fit_budget(plan, budget);
    build_and_check(plan);
  }
}

protocols::DesignedParams designed_params(const CalibrationPlan& plan, const PlannedExperiment& e,
                                          const protocols::ChirpPlan& chirp, const protocols::AxisPrior* fine_mode) {
  const auto& profile = plan.profile.profile;
  if (e.protocol == "axis-sweep") {
    const auto envelope = e.locates.empty() ? fine_envelope(plan, e) : std::nullopt;
    if (!envelope) return protocols::design_axis_sweep(profile, e.axis, plan.design_scale);
    return protocols::design_axis_fine_sweep(profile, e.axis, fine_mode ? *fine_mode : plan.axis_prior, *envelope,
                                             plan.design_scale);
  }
  if (e.protocol == "liquefier-flow-sweep")
    return protocols::design_flow_sweep(profile, plan.liquefier_prior, plan.design_scale);
  if (e.protocol == "liquefier-chirp") return protocols::design_chirp(chirp.expected_tau_s, plan.design_scale);
  return {};
}

protocols::RunOptions experiment_run_options(const CalibrationPlan& plan, const PlannedExperiment& e,
                                             const protocols::ChirpPlan& chirp, bool dry,
                                             const protocols::AxisPrior* fine_mode) {
  const CalibrateArgs& a = plan.options;
  protocols::RunOptions o;
  o.protocol = e.protocol;
  o.params = e.params;
  o.axis = e.axis.empty() ? "x" : e.axis;
  o.machine = plan.sim ? "sim" : a.profile;
  o.profile = plan.profile.profile;  // with "sim": the printer the simulator simulates
  o.host = plan.simulator;
  o.port = a.port;
  o.dry_run = dry;
  o.run_dir = plan.run_dir + "/" + e.name;
  o.file_tag = "tunekit";  // raw_data_x_tunekit.csv: names that do not change from run to run
  // The experiment's design (experiment_design.hpp) where --param did not set the parameter.
  for (const auto& [name, value] : designed_params(plan, e, chirp, fine_mode).params)
    if (!e.params.count(name)) o.params[name] = value;
  if (e.protocol == "liquefier-chirp") {
    // Sized from the time constant (the protocol's staircase step as long as the chirp's end
    // allows, never shorter than the machine's: chirp_plan.hpp, machine_defaults) ...
    if (!e.params.count("expected_tau_s")) o.params["expected_tau_s"] = chirp.expected_tau_s;
    // ... with as short a stop as the extruder allows: its own acceleration limit.
    if (plan.profile.profile.extruder.max_accel_mm_s2 > 0 && !e.params.count("accel_mm_s2"))
      o.params["accel_mm_s2"] = plan.profile.profile.extruder.max_accel_mm_s2;
  }
  return o;
}

}  // namespace tunekit::calibration
