// tunekit calibrate: the command line of the command (options bound straight into the library's
// option structs, so --help shows the library's defaults); the work is done by the
// calibration library's stages (calibration_pipeline.hpp), whose progress is drawn here.

#include <memory>
#include <string>

#include "tunekit/calibration/guided/calibrate_command.hpp"
#include "tunekit/calibration/guided/calibration_pipeline.hpp"
#include "tunekit/calibration/presentation/progress.hpp"
#include "tunekit/cli/command.hpp"
#include "tunekit/cli/commands.hpp"
#include "tunekit/cli/option_binding.hpp"

namespace tunekit::cli {

using namespace calibration;

namespace {

// calibrate's stages drawn as a progress bar on a terminal (nothing off one).
class BarProgress final : public Progress {
 public:
  explicit BarProgress(CliContext& ctx) : ctx_(ctx) {}
  void expect(int steps) override { bar_ = std::make_unique<ProgressBar>(ctx_, steps); }
  void begin(const std::string& label, double estimated_s) override {
    if (bar_) bar_->begin(label, estimated_s);
  }
  void end(const std::string& summary) override {
    if (bar_) bar_->end(summary);
  }

 private:
  CliContext& ctx_;
  std::unique_ptr<ProgressBar> bar_;
};

}  // namespace

void register_calibrate(CLI::App& app, CliContext& ctx) {
  auto a = std::make_shared<CalibrateArgs>();
  auto* sub = app.add_subcommand("calibrate", "Guided calibration: experiments, identification, compensators, report");
  sub->add_option("-m,--machine", a->machine, "'sim' (the built-in simulated printer) or a port (with --profile)")
      ->capture_default_str();
  sub->add_option("-p,--profile", a->profile,
                  "Machine profile: tunekit's TOML (limits in mm, mm/s, mm/s^2, and sensors) or the firmware's own "
                  "configuration (Klipper printer.cfg, Marlin M503 report or Configuration.h, RRF config.g); with "
                  "--machine sim the printer to simulate");
  sub->add_option("--param", a->params,
                  "A protocol parameter for one experiment or protocol, EXPERIMENT.NAME=VALUE in the unit the name "
                  "carries (repeatable; 'tunekit run --help' lists them), e.g. axis-x.freq_end_hz=80");
  sub->add_option("--sensor", a->sensors,
                  "A sensor the firmware configuration given as --profile does not list but the machine has: "
                  "accelerometer, load_cell or camera (repeatable)");
  sub->add_flag("--dry-run", a->dry_run,
                "Plan every experiment for the profile's limits, check it, print the plan and stop (nothing is sent)");
  sub->add_option("--budget-s", a->budget_s,
                  "Machine time (s) all experiments may take together; below the design's own the sweeps run faster "
                  "and the holds and the chirp are shorter, and the plan (--dry-run) says how much wider each "
                  "predicted interval becomes")
      ->check(positive_finite("seconds of machine time"));
  sub->add_option("--port", a->port, "Serial device, pseudo-terminal or unix:SOCKET of a real machine");
  sub->add_option("--out", a->out_dir, "Run directory (default: runs/calibrate-UTCSTAMP)");
  sub->add_option("-f,--firmware", a->firmware,
                  "Configuration dialect to update (and the firmware the simulator runs): klipper, kalico, marlin or "
                  "rrf; default: the profile's [machine] firmware, else klipper");
  sub->add_option("-c,--config", a->config,
                  "Firmware configuration to update (default: a copy of the bundled example in the run directory)");
  sub->add_flag("--write", a->write,
                "Apply the configuration change (backup + atomic replace); default: preview the diff");
  sub->add_flag("--skip-liquefier", a->skip_liquefier, "Leave out the liquefier flow sweep and chirp tests");
  sub->add_flag("--skip-axes", a->skip_axes, "Leave out the X and Y resonance sweeps");
  sub->add_flag("--thermal", a->thermal,
                "First of all, the hot end's thermal experiment (heater-identify, five minutes from rest) and model");
  sub->add_option("--heater-power", a->heater_power_w,
                  "With --thermal: the heater's power at full duty (W), the thermal model's given P")
      ->capture_default_str()
      ->check(CLI::Range(1e-3, 1e5));
  sub->add_flag("--keep-heaters", a->keep_heaters,
                "Leave the hot end at the experiments' temperature when they end (default: turned off)");
  sub->add_option("--sim", a->sim_options, "Simulator truth and faults, KEY=VALUE (see 'tunekit run --help')");
  sub->add_option("--liquefier", a->liquefier,
                  "Liquefier path: load-cell (feed steps and chirp against a load cell), camera (printed line and ring "
                  "tests, photographed), auto (load-cell when the profile has one, else camera)")
      ->capture_default_str();
  sub->add_option("--camera", a->camera.camera,
                  "Camera path: 'sim' photographs the simulated printer's print (the default with --machine sim)");
  sub->add_option("--photo", a->camera.photo,
                  "Camera path: a photo of the printed tests from above (bed X to the right)");
  sub->add_option(
      "--camera-device", a->camera.camera_device,
      "Camera path: take the photo with this camera (e.g. /dev/video0; focus and exposure settle, frames averaged)");
  sub->add_option("--px-per-mm", a->camera.px_per_mm, "Camera path: the photo's scale on the bed (px/mm)");
  sub->add_option("--camera-frames", a->camera.frames, "Camera path: frames averaged from --camera-device")
      ->capture_default_str();
  add_output_options(sub, a->output);
  // calibrate measures tau twice (step and frequency response): its example names which one.
  sub->get_option("--require")
      ->description(
          "CI threshold on a result, e.g. 'step.tau_s<0.6' or 'x.freq_hz>=35' (repeatable); exit 1 naming each unmet "
          "one");
  sub->footer(
      "Examples:\n"
      "  tunekit calibrate --machine sim                      # the built-in simulated printer\n"
      "  tunekit calibrate --machine sim --firmware marlin --out runs/demo\n"
      "  tunekit calibrate --machine sim --profile printer.cfg --sensor accelerometer --dry-run  # checked plan\n"
      "  tunekit calibrate --machine sim --profile printer.cfg --param axis-sweep.accel_per_hz=40\n"
      "  tunekit calibrate --machine /dev/ttyACM0 --profile my-printer.toml --firmware marlin \\\n"
      "                    --config Marlin/Configuration_adv.h\n"
      "Liquefier paths (--liquefier):\n"
      "  load-cell  a flow sweep (feed steps up and down through 6 flow levels up to 90 % of the profile's\n"
      "             max_flow_mm3_s, each level reached from both sides: tau, K, theta per level and tau = a u^b)\n"
      "             and a chirp, against a load cell (Klipper: [load_cell], read via load_cell/dump_force)\n"
      "    tunekit calibrate --machine sim --liquefier load-cell\n"
      "    tunekit calibrate --profile klipper-printer.toml --port unix:/tmp/klippy_uds --liquefier load-cell\n"
      "  camera     prints a line test (flow steps along straight lines) and a ring test, then measures a photo:\n"
      "    tunekit calibrate --machine sim --liquefier camera --camera sim        # the simulator photographs its "
      "print\n"
      "    tunekit calibrate --profile p.toml --port /dev/ttyACM0 --liquefier camera --camera-device /dev/video0 \\\n"
      "                      --px-per-mm 12\n"
      "    tunekit calibrate --profile p.toml --port /dev/ttyACM0 --liquefier camera --photo tests.jpg --px-per-mm 12\n"
      "    (on a terminal without --photo/--camera-device it asks for the photo's path once the tests are printed)\n"
      "  auto       load-cell when the profile has one ([sensors] load_cell = true), else camera (the default)\n"
      "Every protocol is checked against the profile before anything is sent. On a terminal each step shows a\n"
      "progress bar with the time left. Then the identified values with their 95 % intervals, the configuration's\n"
      "settings (current, proposed, change), the diff, and what to do next (--json: the JSON results only).");
  sub->callback([a, &ctx] {
    BarProgress progress(ctx);
    set_exit_code(run_calibrate(*a, ctx, progress));
  });
}

}  // namespace tunekit::cli
