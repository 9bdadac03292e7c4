#pragma once
// What each firmware accepts and how its planner runs a move, as data with the source of every
// number: export refuses values outside these ranges (with the bound and its source), the
// shaper recommendation is made among the target firmware's shapers, and the protocols are
// designed within the planner rules. Sources (file and line as read, stated per constant):
//   Klipper v0.13 (Kevin O'Connor et al., Klipper, GPLv3): klippy/extras/shaper_defs.py,
//     klippy/extras/input_shaper.py, klippy/kinematics/extruder.py, klippy/toolhead.py.
//   Marlin 2.1.x / bugfix-2.1.x (MarlinFirmware): Marlin/src/gcode/feature/advance/M900.cpp,
//     Marlin/src/gcode/feature/input_shaping/M593.cpp, Marlin/src/module/stepper.h,
//     Marlin/Configuration.h and Configuration_adv.h defaults, Marlin/src/module/ft_types.h.
//   RepRapFirmware 3.5 (Duet3D): src/Movement/AxisShaper.h/.cpp, src/GCodes/GCodes2.cpp,
//     src/GCodes/GCodes.cpp (WriteConfigOverrideFile), src/Movement/DDA.cpp.

#include <optional>
#include <string>
#include <vector>

#include "tunekit/firmware/firmware_export.hpp"

namespace tunekit::firmware::limits {

/// One input shaper a firmware implements: its name there (as written in the configuration),
/// tunekit's spelling (Klipper's: zv, mzv, zvd, zvdd, ei, 2hump_ei, 3hump_ei; empty when tunekit
/// cannot design it), and the largest damping ratio the firmware accepts for it.
struct FirmwareShaper {
  const char* firmware_name;
  const char* tunekit_name;
  double max_damping;
  const char* source;
};

// --- Klipper ---------------------------------------------------------------------------------
/// klippy/extras/shaper_defs.py, INPUT_SHAPERS (lines 146-159): zv/mzv/zvd max_damping_ratio
/// 0.99, ei 0.4, 2hump_ei 0.3, 3hump_ei 0.2; input_shaper.py line 20-23 enforces them
/// ("must have maximum of ...").
inline constexpr FirmwareShaper kKlipperShapers[] = {
    {"zv", "zv", 0.99, "klippy/extras/shaper_defs.py:147 (max_damping_ratio=0.99)"},
    {"mzv", "mzv", 0.99, "klippy/extras/shaper_defs.py:149 (max_damping_ratio=0.99)"},
    {"zvd", "zvd", 0.99, "klippy/extras/shaper_defs.py:151 (max_damping_ratio=0.99)"},
    {"ei", "ei", 0.4, "klippy/extras/shaper_defs.py:153 (max_damping_ratio=0.4)"},
    {"2hump_ei", "2hump_ei", 0.3, "klippy/extras/shaper_defs.py:155 (max_damping_ratio=0.3)"},
    {"3hump_ei", "3hump_ei", 0.2, "klippy/extras/shaper_defs.py:157 (max_damping_ratio=0.2)"},
};
/// klippy/kinematics/extruder.py:14, getfloat('pressure_advance', 0., minval=0.).
inline constexpr double kKlipperPressureAdvanceMin = 0.0;
/// klippy/kinematics/extruder.py:15-16, 'pressure_advance_smooth_time' above=0., maxval=.200.
inline constexpr double kKlipperSmoothTimeMax_s = 0.2;
/// klippy/kinematics/extruder.py:15, 'pressure_advance_smooth_time' default .040 (Klipper's
/// Pressure_Advance.md: lower values make the extruder more sensitive to noise and skipping).
inline constexpr double kKlipperSmoothTimeDefault_s = 0.040;
/// klippy/extras/input_shaper.py:24, shaper_freq minval=0. (0 disables shaping on the axis).
inline constexpr double kKlipperShaperFreqMin_hz = 0.0;
/// klippy/kinematics/extruder.py:168-169, 'max_extrude_only_distance' default 50 mm; longer
/// extrude-only moves are refused ("Extrude only move too long", extruder.py:218-221).
inline constexpr double kKlipperMaxExtrudeOnlyDistance_mm = 50.0;
/// klippy/toolhead.py:211-212, 'minimum_cruise_ratio' default 0.5; toolhead.py:537
/// mcr_pseudo_accel = max_accel * (1 - minimum_cruise_ratio) caps a short move's peak speed.
inline constexpr double kKlipperMinimumCruiseRatioDefault = 0.5;

// --- Kalico (KalicoCrew/kalico, GPLv3; branch bleeding-edge-v2 as of 2026-06) ---------------------
/// klippy/kinematics/extruder.py ExtruderStepper: config.getchoice("pressure_advance_model",
/// {"linear", "tanh", "recipr"}); PANonLinearModel: linear_advance minval=0., nonlinear_offset
/// minval=0., linearization_velocity above=0. when nonlinear_offset is set.
inline constexpr const char* kKalicoAdvanceModels[] = {"linear", "tanh", "recipr"};
inline constexpr double kKalicoLinearAdvanceMin_s = 0.0;
inline constexpr double kKalicoNonlinearOffsetMin_mm = 0.0;
/// extruder.py: getfloat("pressure_advance_time_offset", 0.0, minval=-0.2, maxval=0.2).
inline constexpr double kKalicoTimeOffsetMin_s = -0.2;
inline constexpr double kKalicoTimeOffsetMax_s = 0.2;

// --- OrcaSlicer (SoftFever/OrcaSlicer, AGPLv3) ---------------------------------------------------
/// src/libslic3r/GCode/AdaptivePAInterpolator.cpp: the interpolated advance is rounded to 3
/// decimals (std::round(pa * 1000.0) / 1000.0) and a negative result falls back to the
/// profile's pressure_advance (AdaptivePAProcessor.cpp). src/libslic3r/PrintConfig.cpp:
/// adaptive_pressure_advance_bridges max = 2; pressure_advance has no bound there beyond the
/// firmware's. tunekit writes table values from 0 up to kOrcaAdvanceMax_s.
inline constexpr int kOrcaAdvanceDecimals = 3;
inline constexpr double kOrcaAdvanceMax_s = 2.0;

// --- Marlin ----------------------------------------------------------------------------------
/// Marlin/src/gcode/feature/advance/M900.cpp: `if (!WITHIN(K, 0, 10)) echo_value_oor('K')`.
inline constexpr double kMarlinAdvanceKMax = 10.0;
/// M900 U (ADVANCE_TAU, SMOOTH_LIN_ADVANCE, bugfix-2.1.x): 0 to 0.5 s.
inline constexpr double kMarlinAdvanceTauMax_s = 0.5;
/// Marlin/src/gcode/feature/input_shaping/M593.cpp: `if (WITHIN(zeta, 0, 1))`, else
/// "?Zeta (D) value out of range (0-1)".
inline constexpr double kMarlinShapingZetaMax = 1.0;
/// Marlin's classic input shaping (stepper.cpp ShapingQueue) is ZV only.
inline constexpr FirmwareShaper kMarlinClassicShapers[] = {
    {"zv", "zv", 1.0, "Marlin/src/gcode/feature/input_shaping/M593.cpp (ZV; T is not implemented)"},
};
/// FT_MOTION (M493) shapers, Marlin/src/module/ft_types.h ftMotionShaper_t:
/// ZV, ZVD, ZVDD, ZVDDD, EI, 2HEI, 3HEI, MZV. The G-code names are those of M493's report.
inline constexpr FirmwareShaper kMarlinFtMotionShapers[] = {
    {"ZV", "zv", 1.0, "Marlin/src/module/ft_types.h (ftMotionShaper_ZV)"},
    {"ZVD", "zvd", 1.0, "Marlin/src/module/ft_types.h (ftMotionShaper_ZVD)"},
    {"ZVDD", "zvdd", 1.0, "Marlin/src/module/ft_types.h (ftMotionShaper_ZVDD)"},
    {"ZVDDD", "", 1.0, "Marlin/src/module/ft_types.h (ftMotionShaper_ZVDDD)"},
    {"EI", "ei", 1.0, "Marlin/src/module/ft_types.h (ftMotionShaper_EI)"},
    {"2HEI", "2hump_ei", 1.0, "Marlin/src/module/ft_types.h (ftMotionShaper_2HEI)"},
    {"3HEI", "3hump_ei", 1.0, "Marlin/src/module/ft_types.h (ftMotionShaper_3HEI)"},
    {"MZV", "mzv", 1.0, "Marlin/src/module/ft_types.h (ftMotionShaper_MZV)"},
};
/// Configuration_adv.h MIN_STEPS_PER_SEGMENT 6: moves with fewer steps are joined with the next.
inline constexpr int kMarlinMinStepsPerSegment = 6;
/// Configuration_adv.h DEFAULT_MINSEGMENTTIME 20000 us (M205 B): shorter moves are slowed.
inline constexpr double kMarlinDefaultMinSegmentTime_s = 0.020;
/// Configuration.h DEFAULT_MAX_ACCELERATION { 3000, 3000, 100, 10000 } (M201): caps M204.
inline constexpr double kMarlinDefaultMaxAccelXY_mm_s2 = 3000.0;
/// Configuration.h DEFAULT_AXIS_STEPS_PER_UNIT { 80, 80, 400, 500 } (M92).
inline constexpr double kMarlinDefaultStepsPerMmXY = 80.0;
/// Configuration.h DEFAULT_RETRACT_ACCELERATION 3000 (M204 R): the acceleration of moves
/// without X/Y/Z steps (planner.cpp: `if (block->steps.a|b|c == 0) accel = retract_acceleration`).
inline constexpr double kMarlinDefaultRetractAccel_mm_s2 = 3000.0;

// --- RepRapFirmware ----------------------------------------------------------------------------
/// src/Movement/AxisShaper.h NamedEnum InputShaperType: custom, ei2, ei3, mzv, none, zvd, zvdd,
/// zvddd. Damping S is limited to 0-0.99 (AxisShaper.cpp:97, TryGetLimitedFValue('S', zeta, ..., 0.0, 0.99)).
inline constexpr FirmwareShaper kRrfShapers[] = {
    {"mzv", "mzv", 0.99, "src/Movement/AxisShaper.h InputShaperType::mzv"},
    {"zvd", "zvd", 0.99, "src/Movement/AxisShaper.h InputShaperType::zvd"},
    {"zvdd", "zvdd", 0.99, "src/Movement/AxisShaper.h InputShaperType::zvdd"},
    {"zvddd", "", 0.99, "src/Movement/AxisShaper.h InputShaperType::zvddd"},
    {"ei2", "2hump_ei", 0.99, "src/Movement/AxisShaper.h InputShaperType::ei2"},
    {"ei3", "3hump_ei", 0.99, "src/Movement/AxisShaper.h InputShaperType::ei3"},
};
/// src/Movement/AxisShaper.cpp:81, StepClockRate / (2 * 65535) (16-bit half period); with the
/// Duet 2 step clock of 937500 Hz.
inline constexpr double kRrfShaperFreqMin_hz = 937500.0 / (2 * 65535.0);
/// src/Movement/AxisShaper.cpp:82, MaximumInputShapingFrequency = 1000.0.
inline constexpr double kRrfShaperFreqMax_hz = 1000.0;
/// src/Movement/AxisShaper.cpp:97, S limited to 0..0.99.
inline constexpr double kRrfShaperZetaMax = 0.99;
/// M572 S: pressure advance in seconds, not negative (GCodes2.cpp case 572).
inline constexpr double kRrfPressureAdvanceMin = 0.0;

/// The firmware's shapers (Marlin: classic, or FT_MOTION's with `ft_motion`).
std::vector<FirmwareShaper> shapers_of(ExportFirmware fw, bool ft_motion = false);
/// The entry for tunekit's shaper name `type` (Klipper spelling), or nullopt when the firmware
/// lacks it.
std::optional<FirmwareShaper> find_shaper(ExportFirmware fw, const std::string& type, bool ft_motion = false);
/// "zv, mzv, ..." in the firmware's spelling, for messages.
std::string shaper_list(ExportFirmware fw, bool ft_motion = false);
/// The firmware's display name: "Klipper", "Marlin", "RepRapFirmware".
std::string firmware_title(ExportFirmware fw);

}  // namespace tunekit::firmware::limits
