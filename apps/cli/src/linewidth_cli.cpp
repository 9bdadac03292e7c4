// tunekit linewidth: the command line of the command (options bound straight into the library's
// option structs, so --help shows the library's defaults); the work is done by the
// calibration library's compute function.

#include "tunekit/cli/command.hpp"
#include "tunekit/cli/analysis_commands.hpp"
#include "tunekit/cli/commands.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/analyses/linewidth_command.hpp"
#include "tunekit/cli/option_binding.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/machine/gcode.hpp"
#include "tunekit/vision/camera_calibration.hpp"
#include "tunekit/vision/charuco.hpp"
#include "tunekit/vision/image_io.hpp"
#include "tunekit/vision/line_width.hpp"
#include "tunekit/vision/overlay.hpp"
#include "tunekit/vision/width_to_dynamics.hpp"
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <limits>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <optional>

namespace tunekit::cli {

using namespace calibration;

namespace {

struct LinewidthCommand {
  LinewidthOptions options;
  OutputOptions output;
};

// The image's scale and geometry: its size limit, px/mm, a camera profile, a chessboard or
// ChArUco board, a reference width, rectification.
void add_scale_options(CLI::App* sub, LinewidthOptions& o) {
  sub->add_option("--max-image-mp", o.max_image_mp,
                  "Refuse images whose header claims more pixels than this, before decoding (megapixels)")
      ->capture_default_str();
  auto* ppm = sub->add_option("--px-per-mm", o.px_per_mm, "Image scale on the bed plane (px/mm)");
  ppm->check(CLI::PositiveNumber);
  sub->add_option("--camera", o.camera,
                  "Camera profile (JSON from --save-camera): removes lens distortion; its bed plane gives the scale "
                  "(px/mm)");
  sub->add_option("--chessboard", o.chessboard,
                  "Chessboard in the scene (or, with --save-camera, in the calibration photos): inner corners "
                  "COLSxROWS, e.g. 9x6");
  sub->add_option("--square-mm", o.square_mm, "Side of a chessboard or ChArUco square (mm)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--charuco", o.charuco,
                  "ChArUco board in the scene instead of a chessboard: squares SQUARESxSQUARES, e.g. 5x7 (found when "
                  "partly covered or partly outside the picture; needs OpenCV's aruco module)");
  sub->add_option("--marker-mm", o.marker_mm, "Side of a ChArUco board's ArUco markers (mm)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--aruco-dict", o.aruco_dict, "ArUco dictionary of the ChArUco board")->capture_default_str();
  sub->add_option("--reference-width-mm", o.reference_width_mm,
                  "Scale from a reference: the longest line in the image has this width (mm)")
      ->check(CLI::PositiveNumber);
  sub->add_flag("--rectify", o.rectify,
                "Warp the photo onto the bed plane first (perspective of a tilted camera; needs --chessboard or a "
                "--camera bed plane)");
}

// How lines are found and what is written besides the widths: polarity, sampling, edges,
// overlays, a camera calibration.
void add_detection_options(CLI::App* sub, LinewidthOptions& o) {
  add_choice_option<vision::LinePolarity>(sub, "--polarity", o.detection.polarity,
                                          {{"auto", vision::LinePolarity::automatic},
                                           {"dark", vision::LinePolarity::dark},
                                           {"light", vision::LinePolarity::light}},
                                          "Line brightness against the bed: auto, dark or light");
  sub->add_option("--step-px", o.detection.step_px, "Spacing of profile samples along the line (px)")
      ->capture_default_str()
      ->check(CLI::Range(0.25, 100.0));
  sub->add_option("--min-length-px", o.detection.min_length_px, "Ignore features shorter than this (px of centreline)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  sub->add_flag(
      "--allow-edge", o.allow_edge,
      "Measure lines that touch the frame edge (their out-of-frame stretches are flagged) instead of failing");
  sub->add_option("--overlay", o.overlay_dir,
                  "Write check images (edges, centreline, flags) to this directory as <image>_overlay.png");
  sub->add_option("--save-camera", o.save_camera,
                  "Calibrate the camera from the IMAGES (chessboard photos; the first lies on the bed) and write the "
                  "profile (JSON) here; nothing is measured");
}

// A line's profile against time (--profile-csv): which line, the speed and the set-point.
void add_profile_options(CLI::App* sub, LinewidthOptions& o) {
  sub->add_option(
      "--profile-csv", o.profile_csv,
      "Write line --line's profile against time: columns time (s), s (mm), width (mm), setpoint_width (mm), "
      "confidence");
  sub->add_option("--line", o.line, "Line (1 = longest) written by --profile-csv")->check(CLI::PositiveNumber);
  sub->add_option("--speed-mm-s", o.speed_mm_s, "Commanded print speed along the line (mm/s)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--setpoint-width-mm", o.setpoint_width_mm,
                  "Set-point (G-code) line width (mm); default: the measured mean")
      ->check(CLI::PositiveNumber);
}

// Holtrup's ring print: the sines, the amplitude, the geometry and the direction.
void add_ring_options(CLI::App* sub, LinewidthOptions& o) {
  sub->add_option("--ring-sines", o.ring_sines, "Ring print: sines per rotation N (Holtrup 2019 eq. 4.2; 1)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--ring-amplitude-mm", o.ring_amplitude_mm, "Ring print: feeder offset amplitude A (mm)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--ring-radius-mm", o.ring_radius_mm, "Ring print: ring radius R (mm); default: measured")
      ->check(CLI::PositiveNumber);
  sub->add_option("--rod-radius-mm", o.rod_radius_mm, "Ring print: feed rod (filament) radius (mm)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--layer-height-mm", o.layer_height_mm, "Ring print: layer height (mm)")->check(CLI::PositiveNumber);
  sub->add_option("--ring-flow-amplitude", o.ring_flow_amplitude,
                  "Ring print: the extrusion modulated by (1 + A sin(N theta)) instead of the feeder offset (tunekit's "
                  "ring-print protocol, parameter amplitude); needs --setpoint-width-mm")
      ->check(CLI::Range(0.0, 1.0));
  sub->add_option("--ring-segments", o.ring_segments,
                  "Ring print: straight segments per turn, the set-point constant along each (ring-print parameter "
                  "segments); default: a smooth ring")
      ->check(CLI::PositiveNumber);
  sub->add_option("--ring-start-deg", o.ring_start_deg,
                  "Ring print: where theta = 0 is, as an angle in the photo (deg, counterclockwise from +x)");
  sub->add_flag("--ring-clockwise", o.ring_clockwise, "Ring print: the nozzle ran clockwise as seen in the photo");
}

// A line printed along a G-code path: the file, the filament and where the profile lies on it.
void add_path_options(CLI::App* sub, LinewidthOptions& o) {
  sub->add_option("--gcode", o.gcode,
                  "G-code that printed the line (with --profile-csv): its extruding moves give the commanded speed "
                  "(F, mm/min in the file) along the path, and with --filament-diameter-mm and --layer-height-mm the "
                  "set-point width E (pi d^2/4) / (L h) (mm)");
  sub->add_option("--filament-diameter-mm", o.path.filament_diameter_mm,
                  "With --gcode: filament diameter d (mm) for the set-point width from the feed")
      ->check(CLI::PositiveNumber);
  sub->add_option("--path-offset-mm", o.path.offset_mm,
                  "With --gcode: path length (mm) before the profile's first sample; default: profile centred on the "
                  "path");
  sub->add_flag("--path-reversed", o.path.reversed,
                "With --gcode: the nozzle ran from the profile's end (right/bottom in the photo) to its start");
}

}  // namespace

CLI::App* add_linewidth_command(CLI::App& app, LinewidthOptions& o, OutputOptions& output) {
  auto* sub = app.add_subcommand("linewidth", "Calibrated width profiles of printed lines from photos");
  sub->add_option("images", o.images,
                  "Photos of printed lines (PNG, JPEG, BMP, PNM; PNG and PNM may be 16 bit; TIFF: convert to PNG)")
      ->required();
  add_scale_options(sub, o);
  add_detection_options(sub, o);
  add_profile_options(sub, o);
  add_ring_options(sub, o);
  add_path_options(sub, o);
  add_output_options(sub, output);
  sub->footer(
      "Examples:\n"
      "  tunekit linewidth lines.png --px-per-mm 20 --json --overlay check/\n"
      "  tunekit linewidth bed.jpg --chessboard 9x6 --square-mm 5 --rectify --overlay check/\n"
      "  tunekit linewidth calib*.png --chessboard 9x6 --square-mm 5 --save-camera cam.json\n"
      "  tunekit linewidth shot.png --camera cam.json --json -o widths.json\n"
      "  tunekit linewidth ring.png --px-per-mm 20 --speed-mm-s 10 --ring-sines 3 --ring-amplitude-mm 0.08 \\\n"
      "      --rod-radius-mm 2.5 --layer-height-mm 0.2 --setpoint-width-mm 0.66 --profile-csv ring.csv\n"
      "  tunekit freq ring.csv --time time --output width --input setpoint_width --freq-hz 0.159 --json\n"
      "  tunekit linewidth liquefier-camera/photo.png --px-per-mm 12 --speed-mm-s 20 --ring-sines 6 \\\n"
      "      --ring-radius-mm 30 --ring-flow-amplitude 0.3 --ring-segments 360 --setpoint-width-mm 0.45 --json\n"
      "  tunekit linewidth line.png --px-per-mm 20 --gcode line.gcode --filament-diameter-mm 1.75 \\\n"
      "      --layer-height-mm 0.2 --profile-csv line.csv && tunekit step line.csv --time time \\\n"
      "      --input setpoint_width --output width --json\n"
      "Exit codes: 0 measured, 1 nothing measured (no line found), 2 bad input (unreadable image, line touching\n"
      "the frame edge, scale target not found).");
  return sub;
}

void register_linewidth(CLI::App& app, CliContext& ctx) {
  auto cmd = std::make_shared<LinewidthCommand>();
  add_linewidth_command(app, cmd->options, cmd->output)->callback([cmd, &ctx] {
    set_exit_code(report_outcome(compute_linewidth(cmd->options, ctx.err), cmd->output, ctx));
  });
}

}  // namespace tunekit::cli
