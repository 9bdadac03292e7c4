#pragma once
// The simulated printer's camera: what the simulator printed, photographed from above. The
// bead laid down at every simulation step has the width the simulated liquefier's output flow
// gives at the nozzle's speed, w = Q_out / (v h) (h the nozzle height above the bed, a
// rectangular bead), so the photo carries the liquefier's true width response. The picture is
// made like a real one: light filament on a textured dark bed, the bead blurred by the lens and
// then integrated over each pixel's area (in that order, as a camera forms it), vignetting, a
// lighting gradient across the frame and sensor noise.
//
//   auto bed = std::make_shared<SimPrintBed>();
//   RunOptions o; o.sim_bed = bed; run_experiment(o);        // every printed run lands on it
//   cv::Mat photo = bed->photograph(SimCameraOptions{});      // 8-bit grey
//
// The camera looks straight down: image x runs along the bed's +X, image y along -Y, at
// `px_per_mm`; the frame covers everything printed plus a margin.
//
// Uses OpenCV types (cv::Mat): code that includes this header links tunekit_vision as well
// (protocols links it privately).

#include <array>
#include <mutex>
#include <vector>

#include <opencv2/core.hpp>

namespace tunekit::sim {

struct SimCameraOptions {
  double px_per_mm = 12;        ///< image scale on the bed (px/mm)
  double margin_mm = 8;         ///< frame margin around the print (mm)
  double bed_level = 55;        ///< mean bed brightness (0..255)
  double filament_level = 205;  ///< filament brightness (0..255)
  double vignetting = 0.30;     ///< relative darkening at the frame corners
  double gradient = 0.18;       ///< relative lighting change across the frame (left to right)
  double noise_sigma = 3.0;     ///< sensor noise (grey levels)
  double blur_px = 0.6;         ///< lens blur across the bead (Gaussian sigma, px), before the pixels
  unsigned seed = 7;
};

/// Where the camera put the bed: image px = ((x - x0_mm) * ppm, (y1_mm - y) * ppm).
struct SimCameraFrame {
  double x0_mm = 0, y1_mm = 0, px_per_mm = 0;
  cv::Size size;
};

class SimPrintBed {
 public:
  /// `noise_seed` (the simulator's seed) joins the photo options' seed in drawing the sensor
  /// noise, so that each simulated run's photo has its own noise; 0 keeps the options' seed alone.
  explicit SimPrintBed(unsigned noise_seed = 0) : noise_seed_(noise_seed) {}
  /// One simulation step (see Simulator::deposit_sink). Thread-safe.
  void deposit(double t_s, const std::array<double, 4>& pos, double speed_xy_mm_s, double flow_out_mm3_s);
  /// Number of bead pieces laid down.
  std::size_t pieces() const;
  /// The photo (CV_8U, one channel). An empty bed still gives a photo (of the bed alone, the
  /// frame then covers 100 x 100 mm around the origin).
  cv::Mat photograph(const SimCameraOptions& options, SimCameraFrame* frame = nullptr) const;

 private:
  struct Piece {
    double x0, y0, x1, y1, width_mm;
  };
  unsigned noise_seed_ = 0;
  mutable std::mutex mu_;
  std::vector<Piece> pieces_;
  // The piece being accumulated (consecutive steps are merged into ~0.05 mm pieces).
  bool open_ = false;
  double ox_ = 0, oy_ = 0, lx_ = 0, ly_ = 0, wsum_ = 0, len_ = 0;
};

}  // namespace tunekit::sim
