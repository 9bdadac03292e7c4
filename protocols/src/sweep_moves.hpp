#pragma once
// The axis sweep's motion, planned as Klipper's resonance test plans it (O'Connor, Butyugin et
// al., Klipper 3D printer firmware, klippy/extras/resonance_tester.py as of 2026-08-07): the
// vibration pulses of VibrationPulseTestGenerator.gen_test, the slow sweeping motion that
// SweepingVibrationsTestGenerator.gen_test adds to them (since 6 December 2024), and the moves
// ResonanceTestExecutor.run_test makes of the sum, written as G1 moves whose speeds and
// junctions a planner follows. Not installed; used by experiments_axis.cpp.

#include <map>
#include <string>
#include <vector>

namespace tunekit::protocols::experiment_gcode {

/// Klipper's defaults for X and Y ([resonance_tester] sweeping_accel, sweeping_period; Z has
/// sweeping_accel_z 50 mm/s^2, which tunekit's X/Y sweep does not use).
inline constexpr double kKlipperSweepingAccel_mm_s2 = 400;
inline constexpr double kKlipperSweepingPeriod_s = 1.2;

/// The sweep's design. Frequencies Hz, rate Hz/s, accel_per_hz mm/s^2 per Hz, sweeping_accel
/// mm/s^2, sweeping_period s (0 in either turns the sweeping motion off). min_half_mm: the
/// shortest distance a half period of the pulses may cover (Marlin's MIN_STEPS_PER_SEGMENT; 0
/// elsewhere), which raises the acceleration of the highest frequencies; max_accel_mm_s2 is
/// the axis limit. The pulses' acceleration accel_per_hz f is held at what that limit leaves
/// them beside the sweeping motion (pulse_accel_cap) above the frequency where it meets it; a
/// raised acceleration above the cap is refused (InputError).
struct SweepDesign {
  double freq_start_hz = 0, freq_end_hz = 0, hz_per_sec = 0, accel_per_hz = 0;
  double sweeping_accel_mm_s2 = 0, sweeping_period_s = 0;
  double min_half_mm = 0, max_accel_mm_s2 = 0;
  bool sweeping() const { return sweeping_accel_mm_s2 > 0 && sweeping_period_s > 0; }
  /// The pulses' highest acceleration, mm/s^2: the axis limit less the sweeping motion's.
  double pulse_accel_cap() const { return max_accel_mm_s2 - (sweeping() ? sweeping_accel_mm_s2 : 0.0); }
  /// The frequency (Hz) above which the pulses' acceleration is held at pulse_accel_cap().
  double held_above_hz() const { return pulse_accel_cap() / accel_per_hz; }
};

/// The design as an axis-sweep's parameters state it (freq_start_hz, freq_end_hz, hz_per_sec,
/// accel_per_hz, sweeping_accel, sweeping_period), under the axis limit max_accel_mm_s2; the
/// firmware's own adjustments (min_half_mm) are the caller's.
SweepDesign sweep_design_from_params(const std::map<std::string, double>& params, double max_accel_mm_s2);

/// One piece of constant commanded acceleration: it ends at t_end_s (from the sweep's start),
/// accel_mm_s2 signed along the axis, during the pulse of frequency freq_hz.
struct SweepSegment {
  double t_end_s = 0, accel_mm_s2 = 0, freq_hz = 0;
};

/// One G1 move of the sweep: signed distance along the axis (mm), acceleration (mm/s^2, > 0),
/// the speed cap F (mm/s) and the speeds at its ends (mm/s, >= 0). stop_after: the planner must
/// come to rest at its end although the next move goes on in the same direction (G4 P0).
/// accel_mm_s2 0: a cruise at the acceleration in force. dwell_s > 0: no move, a rest (s).
/// duration_s: its time as planned, s.
struct SweepMove {
  double dist_mm = 0, accel_mm_s2 = 0, feed_mm_s = 0, v_start = 0, v_end = 0;
  bool stop_after = false;
  double dwell_s = 0, duration_s = 0;
};

/// The pulses alone: a quarter period 1/(4f) at +a, one at -a (a = accel_per_hz f, raised to
/// cover min_half_mm), the sign alternating each half period; f rises by hz_per_sec / (2 f)
/// per half period while f <= freq_end_hz.
std::vector<SweepSegment> vibration_pulses(const SweepDesign& d);
/// `pulses` with the sweeping motion added: +-sweeping_accel switching first after
/// period sqrt(2)/8, then after period (sqrt(2)/8 + 1/4), then every half period; unchanged when
/// the sweeping motion is off.
std::vector<SweepSegment> add_sweeping(const std::vector<SweepSegment>& pulses, const SweepDesign& d);
/// The moves of `segments` from rest, ending with a stop at stop_accel_mm_s2 in the direction
/// of motion when the sequence ends moving.
std::vector<SweepMove> sweep_moves(const std::vector<SweepSegment>& segments, double stop_accel_mm_s2);

/// The largest excursion of the sweeping motion alone from its start, mm: sweeping_accel
/// period^2 / 32 (its velocity is a triangle wave of amplitude sweeping_accel period / 4).
double sweeping_excursion_mm(const SweepDesign& d);

}  // namespace tunekit::protocols::experiment_gcode
