#pragma once
// The simulator's named constants, shared by its source files (simulator.cpp: options, truth
// and the pseudo-terminal; sim_plant.cpp: motion and the physical models; sim_gcode.cpp: the
// G-code command table; sim_faults.cpp: fault injection). Where a value mimics a firmware, its
// comment names the firmware source it comes from.

#include <array>
#include <chrono>
#include <cstddef>

namespace tunekit::sim::sim {

// --- Options and truth ---
/// Damping ratio an input shaper is designed for when "shaper_x=TYPE:FREQ" gives none: Klipper's
/// klippy/extras/shaper_defs.py DEFAULT_DAMPING_RATIO.
inline constexpr double kDefaultShaperDamping = 0.1;
/// Share of an axis' response a mode has when "mode_x=FREQ:ZETA" gives no weight: all of it.
inline constexpr double kDefaultModeWeight = 1.0;
/// Feeds (mm/s) at which truth.json tabulates the physics liquefier's local gain and time
/// constant: the range of feeds a step or sweep experiment commands.
inline constexpr std::array<double, 6> kTruthOperatingFeeds_mm_s{0.5, 1.0, 2.0, 3.0, 4.0, 5.0};

// --- Plant ---
/// The hot end is run in chunks of this much machine time (s), not every simulation step: its
/// time constants are seconds.
inline constexpr double kHeaterChunk_s = 0.01;
/// The hot end's thermistor noise is drawn from its own generator, seeded from the simulator's
/// seed times this (odd, so that seeds map to distinct streams).
inline constexpr unsigned kHeaterNoiseSeedFactor = 7919;
/// Marlin's M105 reports the heater's soft PWM as "@:" in 0..127 (temperature.cpp: the
/// soft_pwm_amount, the PID's 0..255 output halved).
inline constexpr double kMarlinPwmReportMax = 127;
/// Marlin's longest temperature auto-report interval, s (AutoReporter::set_interval's limit).
inline constexpr double kMarlinAutoReportMax_s = 60;
/// M106 S: the fan's duty in 0..255 (Marlin, Klipper; RepRapFirmware reads S <= 1 as a fraction).
inline constexpr double kFanFullScale = 255;
/// Lowest feed (filament mm/s) at which the FOPDT liquefier's flow-dependent time constant is
/// evaluated: a stopped extruder relaxes at this feed's time constant instead of an infinite one.
inline constexpr double kTauFloorFeed_mm_s = 0.2;
/// Simulation steps per accelerometer sample: the axes' modes are integrated (RK4) at four
/// times the sample rate so that a mode near the sample rate's Nyquist frequency stays accurate.
inline constexpr int kStepsPerAccelSample = 4;
/// Cosine of the angle between two moves above which the junction counts as straight (the
/// moves blend at the first move's speed); below its negative it is a reversal (RRF).
inline constexpr double kStraightJunctionCos = 0.999;
/// The accelerometer's Z reading at rest (mm/s^2): 1 g, rounded to 9810 as the simulated
/// accelerometer reports it (the sensor, not the printer, defines 1 g; see kStandardGravity).
inline constexpr double kAccelRestZ_mm_s2 = 9810.0;
/// Standard gravity (mm/s^2) by which an RRF M956 run converts mm/s^2 into g
/// (src/Accelerometers/Accelerometers.cpp writes samples in g).
inline constexpr double kStandardGravity_mm_s2 = 9806.65;
/// Bytes of sensor lines buffered before they are written: long moves stream their samples
/// while they run and the buffer stays small.
inline constexpr std::size_t kOutputFlushBytes = 32768;
/// Lowest peak speed (mm/s) a move is planned with: a zero feed would divide by zero in the
/// velocity profile.
inline constexpr double kMinPeakSpeed_mm_s = 1e-6;
/// Slack on the number of whole steps a move lasts: a duration that is a whole number of steps
/// up to rounding is not cut one step short.
inline constexpr double kStepCountSlack = 1e-9;

// --- Firmware rules (G-code command table) ---
/// Marlin Configuration.h DEFAULT_MAX_ACCELERATION {3000, 3000, 100, 10000} and
/// DEFAULT_RETRACT_ACCELERATION 3000, applied as G-code when the simulator starts unless the
/// simulated machine's profile sets its own (SimConfig::acceleration_gcode).
inline constexpr double kMarlinDefaultMaxAccelXY_mm_s2 = 3000;
inline constexpr double kMarlinDefaultMaxAccelE_mm_s2 = 10000;
inline constexpr double kMarlinDefaultRetractAccel_mm_s2 = 3000;
inline constexpr double kDefaultMaxAccelZ_mm_s2 = 100;
/// RepRapFirmware: the M201 of a typical config.g (X/Y 3000, E 3000).
inline constexpr double kRrfDefaultMaxAccelXY_mm_s2 = 3000;
inline constexpr double kRrfDefaultMaxAccelE_mm_s2 = 3000;
/// Marlin Configuration_adv.h MIN_STEPS_PER_SEGMENT: a move with fewer steps is joined with the
/// next (planner.cpp).
inline constexpr long kMarlinMinStepsPerSegment = 6;
/// Marlin Configuration_adv.h DEFAULT_MINSEGMENTTIME (us): M205 B's value when B has none.
inline constexpr double kMarlinDefaultMinSegmentTime_us = 20000;
/// Seconds per microsecond (M205 B is in us).
inline constexpr double kSecondsPerMicrosecond = 1e-6;
/// RepRapFirmware src/Config/Configuration.h MinimumJerk (mm/s): M566 never sets less
/// (Platform.h: zero or negative values make Move loop indefinitely).
inline constexpr double kRrfMinimumJerk_mm_s = 0.1;
/// M566's value (mm/min) when its X or Y word has none: 15 mm/s, the simulator's default jerk.
inline constexpr double kRrfDefaultJerk_mm_min = 900;
/// Seconds per minute (M566 is in mm/min).
inline constexpr double kSecondsPerMinute = 60.0;
/// Marlin ftMotionShaper_t's last value (8, MZV): M493 X/Y above it is an invalid shaper.
inline constexpr int kFtmLastShaper = 8;
/// The file an RRF M956 without F"name" writes: <board>_<date>_<time>.csv
/// (src/Accelerometers/Accelerometers.cpp), with the simulated board's clock at 2024-01-01 00:00.
inline constexpr const char* kM956DefaultFileName = "0_2024-01-01_00.00.00.csv";

// --- Faults and serving ---
/// Bit flipped in the character a garble fault corrupts: it changes the character (so the
/// checksum no longer matches) and keeps letters and digits printable.
inline constexpr int kGarbleBit = 0x04;
/// How long the serving loop waits for host bytes before it checks whether to stop.
inline constexpr std::chrono::milliseconds kServeReadPoll{50};
/// After a disconnect fault: time the host gets to read what was sent before the line closes.
inline constexpr std::chrono::milliseconds kDisconnectGrace{300};

}  // namespace tunekit::sim::sim
