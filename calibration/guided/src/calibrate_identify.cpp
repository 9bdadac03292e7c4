// tunekit calibrate, stage 3: identification. Each analysis is the one a user's single command
// makes of the file the run wrote (compute_step, compute_freq, compute_shaper with the command's
// defaults; only the file, its columns, the axis and the target firmware are named), so that
// the command it records in results.json reproduces it from the run directory.
#include <filesystem>
#include <stdexcept>
#include <utility>

#include "calibrate_liquefier.hpp"
#include "calibrate_stages.hpp"
#include "tunekit/core/input_read_scope.hpp"
#include "tunekit/firmware/firmware_export.hpp"

namespace tunekit::calibration {
namespace {

namespace fs = std::filesystem;

std::string relative_to(const std::string& path, const std::string& run_dir) {
  return fs::relative(path, run_dir).generic_string();
}

// The digest an analysis took of the file `path` as it read it (its outcome carries it).
InputDigest read_input(const std::optional<InputDigest>& read, const std::string& path) {
  if (!read || read->path != path) throw std::logic_error("the analysis did not read " + path);
  return *read;
}

InputDigest read_input(const std::vector<InputDigest>& read, const std::string& path) {
  for (const auto& d : read)
    if (d.path == path) return d;
  throw std::logic_error("the analysis did not read " + path);
}

// The command's words for a step or freq analysis of `csv` (columns named as calibrate names them).
Reproduction columns_command(const char* analysis, const std::string& what, const std::string& csv,
                             const std::string& input, const std::string& output, const std::string& run_dir) {
  return {analysis,
          std::string("analysis/") + analysis + ".json",
          what,
          {"tunekit", analysis, relative_to(csv, run_dir), "--input", input, "--output", output}};
}

// The liquefier as the ring's prediction takes it: the whole-record model's gain, dead time and
// tau at the ring's mean feed (its set-point width, the profile's line, laid at the ring's speed
// and layer height), the numbers the summary lists; the pooled fit's when the model was not fitted.
RingModel ring_model(const StepOutcome& widths, const CalibrationPlan& plan, const ExperimentRuns& runs) {
  const auto ring = runs.runs.find("liquefier-ring");
  if (const auto& m = widths.whole_record.model; m && ring != runs.runs.end()) {
    const auto& prm = ring->second.experiment.params;
    const auto& profile = plan.profile.profile;
    if (prm.count("speed_mm_s") && prm.count("z_mm")) {
      const double feed =
          profile.print.line_width_mm * prm.at("z_mm") * prm.at("speed_mm_s") / profile.filament_area_mm2();
      return {m->tau_at(feed), m->model.fit.value("theta_s"), m->tau_stderr_at(feed),
              m->model.fit.param("theta_s").std_error};
    }
  }
  const auto& pooled = widths.analysis.pooled;
  if (!pooled) return {};
  return {pooled->value("tau_s"), pooled->value("theta_s"), pooled->param("tau_s").std_error,
          pooled->param("theta_s").std_error};
}

void identify_camera(const CalibrationPlan& plan, const ExperimentRuns& runs, Identification& id, CliContext& ctx) {
  id.camera = std::make_shared<CameraAnalysis>(analyze_camera_prints(
      plan.run_dir, plan.options.camera, plan.profile.profile, runs.runs, plan.bed, plan.can_prompt, ctx));
  const CameraAnalysis& cam = *id.camera;
  StepOptions so;
  so.file = cam.width_csv;
  so.time_column = "time";
  // The widths as filament feeds (the commanded and the one that lays the measured width): the
  // record in the load-cell path's unit, so its model designs the advance the same way.
  so.input_column = "feed";
  so.output_column = "delivered_feed";
  so.feed_track = cam.feed_track_csv;
  so.analysis.model = fitting::StepModel::fopdt;  // `tunekit step`'s default model
  // The widths and the feed track as the camera analysis wrote them (not read back).
  id.step = calibrate_analysis("step", [&] { return compute_step(so, cam.width_record, &cam.feed_track); });
  const std::string out = plan.run_dir + "/analysis/step.json";
  id.export_inputs.push_back(keep_analysis(*id.step, out, ctx));
  id.inputs.push_back(cam.width_record.digest());
  id.inputs.push_back(cam.photo_input);
  Reproduction r = columns_command("step", "the liquefier's step responses in the printed line widths: tau, K, theta",
                                   cam.width_csv, "feed", "delivered_feed", plan.run_dir);
  r.args.insert(r.args.end(), {"--feed-track", relative_to(cam.feed_track_csv, plan.run_dir)});
  id.inputs.push_back(cam.feed_track.digest());
  id.reproduce.push_back(std::move(r));
  add_ring_prediction(*id.camera, ring_model(*id.step, plan, runs));
}

void identify_load_cell(const CalibrationPlan& plan, const ExperimentRuns& runs, Identification& id, CliContext& ctx) {
  if (runs.liquefier_step) {
    const std::string csv = runs.runs.at("liquefier-step").files.at(protocols::RunFile::load_cell);
    const std::string out = plan.run_dir + "/analysis/step.json";
    id.step = runs.liquefier_step;
    id.export_inputs.push_back(keep_analysis(*id.step, out, ctx));
    id.inputs.push_back({csv, id.step->input_sha256, id.step->input_size_bytes});
    Reproduction r = columns_command("step",
                                     "the liquefier's step responses in the load cell's flow sweep: tau, K, theta "
                                     "per step, pooled and per flow level",
                                     csv, "feed", "force", plan.run_dir);
    if (const std::string& track = id.step->options.feed_track; !track.empty()) {
      r.args.insert(r.args.end(), {"--feed-track", relative_to(track, plan.run_dir)});
      id.inputs.push_back(read_input(id.step->feed_track_input, track));
    }
    id.reproduce.push_back(std::move(r));
  }
  if (const auto it = runs.runs.find("liquefier-chirp"); it != runs.runs.end()) {
    const std::string csv = it->second.files.at(protocols::RunFile::load_cell);
    const std::string out = plan.run_dir + "/analysis/freq.json";
    // Analysed as a user would analyse the file: `tunekit freq FILE --input feed --output force`
    // sizes the analysis from the record itself (where the chirp starts, the band it excites).
    FreqOptions fo;
    fo.file = csv;
    fo.time_column = "time";
    fo.input_column = "feed";
    fo.output_column = "force";
    if (const auto track = it->second.files.find(protocols::RunFile::feed_track); track != it->second.files.end())
      fo.feed_track = track->second;
    id.freq = calibrate_analysis("freq", [&] { return compute_freq(fo); });
    keep_analysis(*id.freq, out, ctx);
    id.inputs.push_back({csv, id.freq->input_sha256, id.freq->input_size_bytes});
    Reproduction r = columns_command("freq",
                                     "the liquefier's frequency response to the chirp and the transfer function "
                                     "fitted to it",
                                     csv, "feed", "force", plan.run_dir);
    if (!fo.feed_track.empty()) {
      r.args.insert(r.args.end(), {"--feed-track", relative_to(fo.feed_track, plan.run_dir)});
      id.inputs.push_back(read_input(id.freq->feed_track_input, fo.feed_track));
    }
    id.reproduce.push_back(std::move(r));
  }
}

void identify_axes(const CalibrationPlan& plan, const ExperimentRuns& runs, Identification& id, CliContext& ctx) {
  // The coarse passes' records as read between the runs (each record opened once).
  const core::InputReadScope read_once;
  for (const auto& [path, bytes] : runs.coarse_bytes) core::InputReadScope::keep(path, bytes);
  for (const char axis : {'x', 'y'}) {
    const auto it = runs.runs.find(std::string("axis-") + axis);
    if (it == runs.runs.end()) continue;
    // The coarse pass' record is the spectrum (the whole band, the shaper is scored against it);
    // the fine pass over the mode's band refines the modes (its fit against its commanded motion).
    std::string csv = it->second.files.at(protocols::RunFile::accel), fine;
    if (const auto coarse = runs.runs.find(std::string("axis-") + axis + "-coarse"); coarse != runs.runs.end())
      fine = std::exchange(csv, coarse->second.files.at(protocols::RunFile::accel));
    const std::string name = std::string("shaper_") + axis;
    const std::string out = plan.run_dir + "/analysis/" + name + ".json";
    // The recommendation is made among the target firmware's shapers (and its damping bounds).
    ShaperOptions so;
    so.accel.files = {csv};
    if (!fine.empty()) so.accel.refine_files = {fine};
    so.accel.input.axis = axis;
    so.firmware = firmware::parse_export_firmware(plan.options.firmware);
    // The proposed maximum acceleration stays within the printer's limit on this axis.
    so.accel_limit_mm_s2 = plan.profile.profile.axis(std::string(1, axis)).max_accel_mm_s2;
    const auto& shaper = id.shapers[axis] = calibrate_analysis("shaper", [&] { return compute_shaper(so); });
    id.export_inputs.push_back(keep_analysis(shaper, out, ctx));
    id.inputs.push_back(read_input(shaper.inputs, csv));
    Reproduction r{name,
                   "analysis/" + name + ".json",
                   std::string("axis ") + axis + "'s resonances (frequency, damping) and the recommended input shaper",
                   {"tunekit", "shaper", relative_to(csv, plan.run_dir), "--axis", std::string(1, axis), "--firmware",
                    plan.options.firmware, "--accel-limit", fmt::format("{:g}", so.accel_limit_mm_s2)}};
    if (!fine.empty()) {
      id.inputs.push_back(read_input(shaper.inputs, fine));
      r.args.insert(r.args.end(), {"--refine-with", relative_to(fine, plan.run_dir)});
    }
    id.reproduce.push_back(std::move(r));
  }
}

// --thermal: the hot end's record as `tunekit thermal` fits it (the held-out part from the run's
// run.json beside it).
void identify_thermal(const CalibrationPlan& plan, const ExperimentRuns& runs, Identification& id, CliContext& ctx) {
  const auto it = runs.runs.find("heater");
  if (it == runs.runs.end()) return;
  const auto file = it->second.files.find(protocols::RunFile::thermal);
  if (file == it->second.files.end()) throw MachineError("the thermal experiment recorded no heater samples");
  ThermalOptions to;
  to.file = file->second;
  to.fit.heater_power_w = plan.options.heater_power_w;
  id.thermal = calibrate_analysis("thermal", [&] { return compute_thermal(to); });
  keep_analysis(*id.thermal, plan.run_dir + "/analysis/thermal.json", ctx);
  id.inputs.push_back(id.thermal->input);
  id.reproduce.push_back({"thermal",
                          "analysis/thermal.json",
                          "the hot end's thermal model (heater, sensor lag, losses) and its held-out prediction",
                          {"tunekit", "thermal", relative_to(to.file, plan.run_dir), "--heater-power",
                           fmt::format("{:g}", to.fit.heater_power_w)}});
}

}  // namespace

std::string Reproduction::command() const {
  std::string out;
  for (const auto& word : args) {
    const bool plain = !word.empty() && word.find_first_not_of(
                                            "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                            "0123456789-_./=:,+@%") == std::string::npos;
    std::string quoted = "'";
    for (char c : word) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
    out += (out.empty() ? "" : " ") + (plain ? word : quoted + "'");
  }
  return out;
}

Identification identify(const CalibrationPlan& plan, const ExperimentRuns& runs, Progress& progress, CliContext& ctx) {
  Identification id;
  progress.begin("identify models", 3);
  if (plan.camera_path) identify_camera(plan, runs, id, ctx);
  identify_load_cell(plan, runs, id, ctx);
  identify_axes(plan, runs, id, ctx);
  identify_thermal(plan, runs, id, ctx);
  progress.end("models identified");
  return id;
}

}  // namespace tunekit::calibration
