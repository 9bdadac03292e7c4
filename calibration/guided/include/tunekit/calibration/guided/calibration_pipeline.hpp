#pragma once
// tunekit calibrate as typed stages, each a function of the previous stages' typed results:
//
//   plan_calibration   the experiments, the run directory and the chirp; every protocol is built
//                      and checked against the machine's limits once, before anything is sent
//   run_experiments    runs them in order (the liquefier step test first: its tau sizes the chirp;
//                      each axis' coarse pass before its fine pass: its mode sets the fine band)
//   identify           the analyses a user's single commands make of the files the runs wrote
//                      (compute_step, compute_freq, compute_shaper with their default options,
//                      only the file and its columns named); typed outcomes
//   design_and_export  pressure advance, input shaping and the configuration change
//   write_run          results.json, plotdata.json, report.html and the history record
//
// run_calibrate() (calibrate_command.hpp) is these five in a row.

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "tunekit/calibration/guided/calibrate_command.hpp"
#include "tunekit/calibration/results/context.hpp"
#include "tunekit/calibration/commands/export_command.hpp"
#include "tunekit/calibration/analyses/freq_command.hpp"
#include "tunekit/calibration/results/input_digest.hpp"
#include "tunekit/calibration/analyses/shaper_command.hpp"
#include "tunekit/calibration/analyses/step_command.hpp"
#include "tunekit/calibration/analyses/thermal_command.hpp"
#include "tunekit/machine/machine_profile.hpp"
#include "tunekit/protocols/chirp_plan.hpp"
#include "tunekit/protocols/experiment_information.hpp"
#include "tunekit/protocols/machine_host.hpp"
#include "tunekit/protocols/runner.hpp"

namespace tunekit::sim {
class SimPrintBed;  // sim/sim_camera.hpp; declared only, so that this header needs no OpenCV
}  // namespace tunekit::sim

namespace tunekit::calibration {

/// How the stages report progress: one begin/end pair per step (each experiment run, then
/// identification, design and writing). The command line draws a ProgressBar (progress.hpp).
class Progress {
 public:
  virtual ~Progress() = default;
  /// How many steps the calibration has; called once, before the first begin().
  virtual void expect(int steps) = 0;
  /// A step starts that is expected to take about `estimated_s` seconds of wall time.
  virtual void begin(const std::string& label, double estimated_s) = 0;
  /// The step ended; `summary` is one short line (a run's status, the report's path).
  virtual void end(const std::string& summary) = 0;
};

/// Progress that shows nothing (a program calling the stages itself).
class SilentProgress final : public Progress {
 public:
  void expect(int) override {}
  void begin(const std::string&, double) override {}
  void end(const std::string&) override {}
};

/// The machine profile a calibration checks its protocols against, and where it came from.
struct CalibrationProfile {
  machine::MachineProfile profile;
  std::string path;    ///< the TOML file (the bundled sim.toml for the built-in simulator)
  InputDigest digest;  ///< of the bytes the profile was read from: export records it, reading nothing again
};

/// --profile, or the built-in simulated printer's; InputError (exit 2) for a real machine without one.
CalibrationProfile load_calibration_profile(const CalibrateArgs& options);

/// One experiment of the calibration.
struct PlannedExperiment {
  std::string name;                      ///< its sub-directory of the run directory, and its label
  std::string protocol;                  ///< protocols::protocol_specs() name
  std::string axis;                      ///< "x" or "y" for the axis sweeps, else empty
  std::map<std::string, double> params;  ///< protocol parameter overrides
  /// An axis' coarse pass: the fine pass (experiment name) whose band the mode it locates sets;
  /// it reports no interval of its own. Empty for every other experiment.
  std::string locates;
  double estimated_s = 0;         ///< the protocol's machine time (s), from its dry run
  protocols::Experiment checked;  ///< the experiment as built and checked by that dry run
  /// Its parameters' 95 % intervals expected from its planned excitation and the plan's priors
  /// (experiment_information.hpp); nullopt for an experiment no prediction is made for.
  std::optional<protocols::ExperimentPrediction> predicted;
  /// With --budget-s below the design's time: the prediction of the design without the budget.
  std::optional<protocols::ExperimentPrediction> unbudgeted;
};

struct CalibrationPlan {
  CalibrateArgs options;
  CalibrationProfile profile;
  bool sim = true;                             ///< the built-in simulated printer
  bool camera_path = false;                    ///< the liquefier is identified from photographed prints
  bool can_prompt = false;                     ///< a terminal can be asked for the photo's path
  OutputOptions output;                        ///< options.output with the history record prepared (--record)
  std::string run_dir;                         ///< created, empty, with analysis/ and config/ (empty: dry run)
  std::vector<PlannedExperiment> experiments;  ///< in the order they run
  /// The chirp as sized from the literature time constant with the machine's staircase step;
  /// run_experiments() sizes it again from the step test's tau, clamped to the range whose
  /// extremes the plan checked (the step and the feed levels do not change with tau), so that
  /// it holds the limits checked before anything was sent.
  protocols::ChirpPlan chirp;
  std::string chirp_basis;  ///< what the chirp was sized from, in words
  /// What the experiments' predicted intervals assume: the plant's typical values and the
  /// sensors' noise and rates (the simulated printer's own sensors with `sim`).
  protocols::LiquefierPrior liquefier_prior;
  protocols::AxisPrior axis_prior;
  /// The experiments' time scale (protocols/experiment_design.hpp): 1, or lower for --budget-s.
  double design_scale = 1;
  /// The simulated camera's print bed (camera path on the simulator), else null.
  std::shared_ptr<sim::SimPrintBed> bed;
  /// The simulated printer every run is made on (with `sim`; simulated_machine.hpp), its options
  /// read once; else null.
  std::shared_ptr<const protocols::MachineHost> simulator;
};

/// Chooses the experiments, creates the run directory and checks every protocol against the
/// profile's limits (one dry run each). InputError (exit 2) before anything is sent.
CalibrationPlan plan_calibration(const CalibrateArgs& options, const CalibrationProfile& profile, bool can_prompt);

struct ExperimentRuns {
  std::map<std::string, protocols::RunResult> runs;  ///< by PlannedExperiment::name
  protocols::ChirpPlan chirp;                        ///< the chirp that ran
  std::string chirp_basis;
  /// Each run's predicted intervals (by PlannedExperiment::name), made before it ran: the chirp's
  /// with the liquefier the step test measured, the others with the plan's priors.
  std::map<std::string, protocols::ExperimentPrediction> predicted;
  /// Each fine pass' mode (by PlannedExperiment::name), located by its coarse pass before it ran:
  /// the mode its band and its predicted intervals were designed from.
  std::map<std::string, protocols::AxisPrior> fine_modes;
  /// The coarse passes' records (and their commanded motion) as read to locate the modes, by
  /// path: the axes' analyses read those bytes again, not the files (each record opened once).
  std::map<std::string, std::string> coarse_bytes;
  /// The load-cell step test identified between the runs (its tau sizes the chirp), as
  /// compute_step() with `tunekit step`'s defaults gives it.
  std::optional<StepOutcome> liquefier_step;
};

/// Runs the plan's experiments in order. MachineError (exit 3) when the machine stops answering.
ExperimentRuns run_experiments(const CalibrationPlan& plan, Progress& progress);

/// The command that reproduces one analysis from the run directory's files, run from the run
/// directory (paths relative to it).
struct Reproduction {
  std::string analysis;           ///< "step", "freq", "shaper_x", "shaper_y"
  std::string json;               ///< the analysis' JSON in the run directory (analysis/NAME.json)
  std::string what;               ///< what the analysis finds, in a few words (for analysis/README)
  std::vector<std::string> args;  ///< the command's words, "tunekit" first
  std::string command() const;    ///< args joined, shell-quoted where needed
};

struct CameraAnalysis;  // calibrate's camera path: the photo's line and ring measurements

struct Identification {
  std::optional<StepOutcome> step;         ///< the liquefier's steps: load-cell flow sweep or line widths
  std::optional<FreqOutcome> freq;         ///< the liquefier chirp's frequency response
  std::map<char, ShaperOutcome> shapers;   ///< per axis ('x', 'y'): modes and the recommended shaper
  std::optional<ThermalOutcome> thermal;   ///< the hot end's thermal model (--thermal)
  std::shared_ptr<CameraAnalysis> camera;  ///< camera path only
  std::vector<InputDigest> inputs;         ///< data files the analyses read, in order, as they read them
  /// The analyses' JSON files export designs from (step and shapers; the frequency response is
  /// compared with the step response, not designed from), in order, as they were written.
  std::vector<InputFile> export_inputs;
  std::vector<Reproduction> reproduce;  ///< one per analysis
};

/// Analyses the runs' files and writes each analysis' JSON (RUN_DIR/analysis/) and a README
/// naming the command that reproduces it. FitError/InputError naming the analysis that failed.
Identification identify(const CalibrationPlan& plan, const ExperimentRuns& runs, Progress& progress, CliContext& ctx);

struct CompensatorDesign {
  ExportOutcome exported;       ///< compensator settings, advance design and the configuration change
  bool marlin_ft_live = false;  ///< Marlin answered M493 with fixed-time motion active
};

/// Designs the compensators and previews (or, with --write, applies) the configuration change;
/// writes RUN_DIR/analysis/export.json and RUN_DIR/config/changes.diff.
CompensatorDesign design_and_export(const CalibrationPlan& plan, const ExperimentRuns& runs,
                                    const Identification& identified, Progress& progress, CliContext& ctx);

/// Writes results.json, plotdata.json and report.html, prints the diff and the report's path,
/// records the run (--record) and returns the exit code (1 for an unmet --require).
int write_run(const CalibrationPlan& plan, const ExperimentRuns& runs, const Identification& identified,
              const CompensatorDesign& design, Progress& progress, CliContext& ctx);

/// The five stages in a row.
int run_calibrate(const CalibrateArgs& options, CliContext& ctx, Progress& progress);

}  // namespace tunekit::calibration
