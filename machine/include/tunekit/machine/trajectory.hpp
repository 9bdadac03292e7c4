#pragma once
// Jerk-limited (S-curve) motion profiles along a path, so the commanded acceleration of every
// protocol move is known exactly. A profile is a list of constant-jerk segments; a move ramps
// from its entry speed to its cruise speed, cruises, and ramps to its exit speed, each ramp
// a 3-segment jerk-limited velocity change (acceleration bounded by a_max, jerk by j_max).
// The simulated printer executes moves with the same profiles. Units: mm, s.

#include <vector>

namespace tunekit::machine {

struct PathState {
  double pos_mm = 0;
  double vel_mm_s = 0;
  double accel_mm_s2 = 0;
};

class Profile {
 public:
  /// Rest-to-rest or blended move of length `distance_mm` >= 0, entering at `v_entry`, leaving
  /// at `v_exit`, cruising at most at `v_max`. When the distance is too short for the ramps the
  /// cruise speed is lowered; if even the entry/exit speeds cannot be met the exit speed is
  /// lowered too.
  static Profile move(double distance_mm, double v_entry, double v_max, double v_exit, double a_max, double j_max);
  /// The duration of that move, s (as move(...).duration_s(), without building its segments).
  static double move_duration_s(double distance_mm, double v_entry, double v_max, double v_exit, double a_max,
                                double j_max);
  /// A pure dwell at speed v (no acceleration) for `duration_s`.
  static Profile cruise(double v, double duration_s);

  double duration_s() const { return duration_; }
  double distance_mm() const;
  double exit_speed() const;
  /// State at time t in [0, duration] (clamped).
  PathState at(double t) const;
  /// Peak |acceleration| reached.
  double peak_accel() const;

  /// One piece of the profile: from `t0_s` (s after the move's start) for `duration_s`, the
  /// acceleration `accel_mm_s2 + jerk_mm_s3 * (t - t0_s)`. The pieces tile [0, duration_s()].
  struct Piece {
    double t0_s, duration_s, accel_mm_s2, jerk_mm_s3;
  };
  std::vector<Piece> pieces() const;

  /// Velocity change v0 -> v1 under a_max, j_max: its duration and distance.
  static double ramp_duration(double v0, double v1, double a_max, double j_max);
  static double ramp_distance(double v0, double v1, double a_max, double j_max);

 private:
  struct Segment {
    double t0, duration, jerk;
    PathState s0;
  };
  void add(double duration, double jerk);
  void add_ramp(double v0, double v1, double a_max, double j_max);
  std::vector<Segment> segs_;
  PathState end_{};
  double duration_ = 0;
};

}  // namespace tunekit::machine
