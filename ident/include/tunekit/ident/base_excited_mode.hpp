#pragma once
// One resonant mode of a motion axis, driven through its base by the commanded acceleration.
//
// The toolhead rides on a spring and damper (natural frequency f, damping ratio zeta) whose base
// follows the commanded motion. Its deflection z (mm) obeys
//     z'' + 2 zeta w z' + w^2 z = -a(t),   w = 2 pi f,
// and an accelerometer on the toolhead reads a + z'' (the base excitation model of a single
// degree of freedom: Rao, Mechanical Vibrations, 2011, section 3.6; Inman, Engineering Vibration,
// 2014, section 2.4). Over a piece of the motion where the commanded acceleration is linear in
// time, a(s) = a0 + j s (a planner's constant-acceleration and constant-jerk phases), the
// response is exact: the particular solution of the linear input, z_p = -(a0 + j s)/w^2 +
// 2 zeta j / w^3, plus the free response of what remains. The simulated printer integrates its
// modes with it, and the output-error fit of a recorded sweep models them with it.

namespace tunekit::ident {

/// Deflection (mm) and its rate (mm/s) of one mode.
struct ModeState {
  double z_mm = 0;
  double v_mm_s = 0;
};

/// The state after h seconds as an affine map of the state before and of the piece's a0 and j.
struct ModeStep {
  double h_s = 0;
  double phi[2][2] = {{1, 0}, {0, 1}};  ///< free response
  double g_accel[2] = {0, 0};           ///< response to a0 = 1 mm/s^2 from rest
  double g_jerk[2] = {0, 0};            ///< response to j = 1 mm/s^3 from rest
};

class BaseExcitedMode {
 public:
  /// freq_hz > 0, zeta > 0 (under-, critically and over-damped modes are all exact).
  BaseExcitedMode(double freq_hz, double zeta);

  double freq_hz() const { return freq_hz_; }
  double zeta() const { return zeta_; }

  /// The state after `h_s` >= 0 seconds under a(s) = a0 + jerk * s.
  ModeState advance(const ModeState& x, double h_s, double a0_mm_s2, double jerk_mm_s3) const;
  /// The affine map of advance() for one step length, to apply many times (apply()).
  ModeStep step(double h_s) const;
  /// The free response's transition over h_s >= 0: the deflection and rate after h_s of a mode
  /// left alone from (z, v) are (phi[0][0] z + phi[0][1] v, phi[1][0] z + phi[1][1] v). One
  /// exponential, sine and cosine for every state moved over the same h_s.
  void free_map(double h_s, double phi[2][2]) const;
  /// advance() with free_map(h_s) given.
  ModeState advance(const ModeState& x, double h_s, double a0_mm_s2, double jerk_mm_s3, const double phi[2][2]) const;
  static ModeState apply(const ModeStep& s, const ModeState& x, double a0_mm_s2, double jerk_mm_s3) {
    return {s.phi[0][0] * x.z_mm + s.phi[0][1] * x.v_mm_s + s.g_accel[0] * a0_mm_s2 + s.g_jerk[0] * jerk_mm_s3,
            s.phi[1][0] * x.z_mm + s.phi[1][1] * x.v_mm_s + s.g_accel[1] * a0_mm_s2 + s.g_jerk[1] * jerk_mm_s3};
  }
  /// The deflection's acceleration z'' at state x under the commanded acceleration a (mm/s^2):
  /// an accelerometer on the toolhead reads a + z''.
  double relative_accel(const ModeState& x, double a_mm_s2) const { return -c_ * x.v_mm_s - k_ * x.z_mm - a_mm_s2; }

 private:
  /// The free response e'' + c e' + k e = 0 over h from (e, e').
  ModeState free_response(const ModeState& e, double h_s) const;

  double freq_hz_, zeta_, w_, c_, k_;
};

}  // namespace tunekit::ident
