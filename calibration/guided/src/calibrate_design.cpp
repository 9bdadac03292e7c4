// tunekit calibrate, stage 4: the compensators (pressure advance and input shaping) and the
// configuration change, previewed unless --write. Export designs from the analyses' typed
// outcomes (design_inputs.hpp), the same values `tunekit export` reads from their JSON files in
// RUN_DIR/analysis/.
#include <algorithm>
#include <filesystem>
#include <map>
#include <sstream>

#include "calibrate_stages.hpp"
#include "tunekit/calibration/commands/design_inputs.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/firmware/firmware_export.hpp"

namespace tunekit::calibration {
namespace {

namespace fs = std::filesystem;

// --config, or a copy of the bundled example configuration of the firmware in RUN_DIR/config/.
std::string configuration_to_update(const CalibrateArgs& a, const std::string& run_dir) {
  if (!a.config.empty()) return a.config;
  const std::map<std::string, std::string> examples{
      {"klipper", "printer.cfg"}, {"kalico", "printer.cfg"}, {"marlin", "Configuration_adv.h"}, {"rrf", "config.g"}};
  const auto it = examples.find(a.firmware);
  if (it == examples.end()) throw InputError("--firmware must be klipper, kalico, marlin or rrf");
  const std::string config = run_dir + "/config/" + it->second;
  const fs::path bundled = bundled_dataset_path("firmware/" + it->second);
  fs::copy_file(bundled, config, fs::copy_options::overwrite_existing);
  return config;
}

/// The analyses' outcomes as export's design inputs, each named by the JSON file it was written to
/// (the file `tunekit export` would read: its digest is recorded as export's input).
DesignInputs typed_design_inputs(const CalibrationPlan& plan, const Identification& identified) {
  DesignInputs d;
  for (const auto& file : identified.export_inputs) {
    d.origins.push_back(file.path());
    d.files.push_back(file.digest());  // of the text written, not read back
  }
  if (identified.step) d.step = step_design_input(*identified.step, plan.run_dir + "/analysis/step.json");
  for (const auto& [axis, outcome] : identified.shapers)
    for (const auto& [label, in] :
         shaper_design_inputs(outcome, plan.run_dir + "/analysis/shaper_" + std::string(1, axis) + ".json"))
      d.axes[label] = in;
  return d;
}

}  // namespace

CompensatorDesign design_and_export(const CalibrationPlan& plan, const ExperimentRuns& runs,
                                    const Identification& identified, Progress& progress, CliContext& ctx) {
  progress.begin("design compensators", 1);
  CompensatorDesign design;
  ExportOptions eo;
  eo.firmware = plan.options.firmware;
  eo.config = configuration_to_update(plan.options, plan.run_dir);
  eo.profile = plan.profile.path;
  eo.loaded_profile = plan.profile.profile;
  eo.loaded_profile_digest = plan.profile.digest;
  // A Marlin printer that answered M493 with fixed-time motion enabled bypasses M593/M900 U:
  // its settings go to M493 (the runner records the answer in each run).
  // The G-code takes the letters of the form that report took (run.json firmware.m493_form).
  const auto live =
      std::find_if(runs.runs.begin(), runs.runs.end(), [](const auto& kv) { return kv.second.ft_motion == "active"; });
  design.marlin_ft_live = live != runs.runs.end() &&
                          firmware::parse_export_firmware(plan.options.firmware) == firmware::ExportFirmware::marlin;
  eo.marlin_ft_live = design.marlin_ft_live;
  if (design.marlin_ft_live) eo.marlin_m493_form = live->second.m493_form;
  eo.write = plan.options.write;
  const DesignInputs inputs = typed_design_inputs(plan, identified);
  design.exported = calibrate_analysis("export", [&] { return compute_export(eo, inputs); });
  OutputOptions keep;
  keep.json = true;  // the summary lines go to the verbose stream only
  keep.output_path = plan.run_dir + "/analysis/export.json";
  std::ostringstream quiet_out, quiet_err;
  CliContext quiet{quiet_out, quiet_err};
  calibrate_analysis("export", [&] { return commit_export(design.exported, keep, quiet); });
  if (ctx.verbosity > 0) print_text(design.exported, ctx.err);
  const std::string& diff = design.exported.change.diff;
  core::write_file_atomic(plan.run_dir + "/config/changes.diff", diff);
  progress.end(diff.empty() ? "configuration already up to date" : "configuration diff ready");
  return design;
}

}  // namespace tunekit::calibration
