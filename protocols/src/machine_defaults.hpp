#pragma once
// The protocols' parameters that come from the machine: every parameter whose default in the
// protocol table is "from the machine" (NaN in protocol_specs.cpp) and that no caller set is
// derived here from the limits in force (the profile, already made stricter by what the firmware
// reported over the link), so that the default experiment of every protocol is one the machine
// can run: feed accelerations within the extruder's, flows within the hot end's, staircase steps
// the extruder keeps, sweep accelerations and speeds within the axis'. Each value's reason is
// recorded in the experiment's excitation ("machine_defaults"). Not installed; used by
// experiments.cpp.

#include "experiment_gcode.hpp"

namespace tunekit::protocols::experiment_gcode {

/// The nominal values the machine defaults start from (a desktop printer's), capped by the limits.
inline constexpr double kNominalStepAccel_mm_s2 = 2000;  ///< feed steps and the flow sweep
inline constexpr double kNominalStepLow_mm_s = 1.0;      ///< the step test's low and high feeds
inline constexpr double kNominalStepHigh_mm_s = 3.0;
inline constexpr double kNominalChirpAccel_mm_s2 = 3000;  ///< sine dwells and the chirp
inline constexpr double kNominalFeedMean_mm_s = 2.0;      ///< sine/chirp mean feed (4.8 mm^3/s at 1.75 mm)
inline constexpr double kNominalFeedAmplitude_mm_s = 1.0;
inline constexpr double kNominalSegment_s = 0.02;  ///< one constant-feed move of a sine/chirp staircase
inline constexpr double kNominalSweepEnd_hz = 100;
inline constexpr double kNominalSineMax_hz = 2;  ///< the sine dwells' highest frequency
/// Klipper's [resonance_tester] accel_per_hz default (klippy/extras/resonance_tester.py), mm/s^2/Hz.
inline constexpr double kKlipperAccelPerHz = 60;
inline constexpr double kNominalTravel_mm_s = 100;
/// The camera path's line test: the room left at each end of the X travel and at the lower end
/// of the Y travel, and how far below the middle of the bed the first line lies (the ring test
/// is printed at the middle).
inline constexpr double kLineClear_mm = 10;
inline constexpr double kLineBelowMiddle_mm = 50;
/// On a firmware that stops after every extrude-only move (Klipper), a staircase step of feed v
/// is run faster so that with its ramps it keeps its time: its peak is at most this factor above
/// v (the step then lasts (1 + e)^2 v / (a e), e the excess).
inline constexpr double kStaircasePeakExcess = 0.25;
/// ... and where its ramps (2 v / a) would take more than this share of a step, the step is the
/// longest a chirp takes (kLongestStaircaseStep_s, the chirp's own cap: chirp_plan.hpp).
inline constexpr double kMaxStopShare = 0.1;
inline constexpr double kLongestStaircaseStep_s = 0.05;

/// Fills in every machine default of `e.params` that is still NaN and the caller did not set,
/// recording each value's reason in e.excitation["machine_defaults"]; the builders fill the
/// positions (centres) themselves.
void fill_machine_defaults(const ExperimentRequest& r, Experiment& e);

/// The highest filament feed the extruder and the hot end allow, mm/s: the lower of the
/// extruder's max_velocity_mm_s and max_flow_mm3_s over the filament's area.
double feed_cap_mm_s(const machine::MachineProfile& profile);

/// The shortest constant-feed move (s) at `feed_mm_s` that a firmware stopping after every
/// extrude-only move runs at acceleration `accel_mm_s2` with its peak at most
/// kStaircasePeakExcess above the feed; 0 where the firmware blends the moves (`stops` false).
double shortest_staircase_step_s(double feed_mm_s, double accel_mm_s2, bool stops);

}  // namespace tunekit::protocols::experiment_gcode
