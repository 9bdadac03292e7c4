#pragma once
// From a width profile to a time signal: the commanded speed along the path
// maps arc length to time, and the feed modulation gives the set-point width the feed implied,
// so `tunekit step` / `tunekit freq` can identify the liquefier from photos.
//
// Ring print of Holtrup 2019 (section 4.3.3): the feeder position gets an offset A sin(N theta)
// with theta the bed's rotary position, so with print speed v on a ring of radius R
// theta = v t / R, the excitation frequency is f = N v / (2 pi R), and the set-point width is
// (eq. 4.3)
//     w_sp(t) = w_gcode - pi A N r_rod^2 cos(N v t / R) / (h R)
// with r_rod the feed rod radius and h the layer height. (Positive feeder offset retracts the
// plunger in that machine; eq. 4.3 is used as printed.)

#include <limits>
#include <string>
#include <vector>

namespace tunekit::vision {

struct RingSine {
  int n_sines = 0;             ///< N: sines per rotation
  double amplitude_mm = 0;     ///< A: feeder offset amplitude (mm of plunger travel)
  double speed_mm_s = 0;       ///< v: print speed under the nozzle (mm/s)
  double radius_mm = 0;        ///< R: ring radius (mm)
  double rod_radius_mm = 0;    ///< r_rod: radius of the feed rod / filament (mm)
  double layer_height_mm = 0;  ///< h (mm)
  double width_gcode_mm = 0;   ///< w_gcode: mean set-point width (mm)
};

/// f = N v / (2 pi R) (Hz).
double ring_frequency_hz(const RingSine& r);
/// Amplitude of the set-point width modulation pi A N r_rod^2 / (h R) (mm).
double ring_setpoint_amplitude_mm(const RingSine& r);
/// Eq. 4.3 (mm) at time t (s) since the nozzle passed theta = 0.
double ring_setpoint_width_mm(const RingSine& r, double t_s);

/// One row of the time profile.
struct TimedWidth {
  double t_s = 0;
  double s_mm = 0;
  double width_mm = 0;
  double setpoint_mm = 0;
  double confidence = 0;
  /// Filament feed (mm/s) per mm of width at this sample: layer height x speed / filament area
  /// (a rectangular bead); NaN when the path's feed is not known.
  double feed_per_width = std::numeric_limits<double>::quiet_NaN();
};

/// Rows of a profile printed at constant speed: t = s / v (s from the path start).
std::vector<TimedWidth> map_constant_speed(const std::vector<double>& s_mm, const std::vector<double>& width_mm,
                                           const std::vector<double>& confidence, double speed_mm_s,
                                           double setpoint_width_mm);

/// One straight piece of a commanded print path (from a G-code file), in print order.
struct PathSegment {
  double length_mm = 0;   ///< XY(Z) length
  double speed_mm_s = 0;  ///< commanded feed rate (acceleration is not modelled)
  double feed_mm = 0;     ///< filament pushed over the segment (E), mm
};

/// How a measured open line lies on the commanded path.
struct PathMapping {
  /// Path length (mm) before the profile's first sample: the line's ends (caps) are not in
  /// the profile. NaN: centre the profile on the path, (path length - profile length) / 2.
  double offset_mm = std::numeric_limits<double>::quiet_NaN();
  bool reversed = false;            ///< the nozzle ran from the profile's last sample to its first
  double filament_diameter_mm = 0;  ///< > 0 with layer_height_mm: set-point from the feed
  double layer_height_mm = 0;
  double setpoint_width_mm = 0;  ///< otherwise this constant set-point
};

/// Set-point width the feed implies on a segment: filament volume over path length and layer
/// height, w = E (pi d^2 / 4) / (L h) (a rectangular bead), mm.
double feed_setpoint_width_mm(const PathSegment& seg, double filament_diameter_mm, double layer_height_mm);

/// Rows of an open line's profile printed along `path`: each sample's position on the path
/// gives the time (piecewise constant speed from the first segment's start) and the set-point
/// width (from the feed: its mean over the sample's window, half-way to each neighbour, so a
/// change between two segments shows in the sample whose window holds it; or constant). Samples
/// off the path are dropped. Rows come out sorted by time. Throws InputError for an empty path or one without length.
std::vector<TimedWidth> map_path(const std::vector<double>& s_mm, const std::vector<double>& width_mm,
                                 const std::vector<double>& confidence, const std::vector<PathSegment>& path,
                                 const PathMapping& how);

/// CSV text with columns `time (s)`, `s (mm)`, `width (mm)`, `setpoint_width (mm)`, `confidence`.
/// When every row knows its feed_per_width, two columns follow: "feed (mm/s)", the set-point in
/// filament feed, and "delivered_feed (mm/s)", the feed that lays the measured width: the record
/// in the load-cell record's input unit, for the liquefier's identification.
std::string timed_width_csv(const std::vector<TimedWidth>& rows, const std::string& comment);

}  // namespace tunekit::vision
