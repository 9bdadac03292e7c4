#pragma once
// Marlin's fixed-time motion (FT_MOTION) as its M493 G-code reports and sets it
// (Marlin/src/gcode/feature/ft_motion/M493.cpp, say_shaping()). The report and the letters that
// set a shaper changed several times in Marlin's development line (bugfix-2.1.x), where
// FT_MOTION came in 2023. The forms, by the period of the source that prints them:
//
//   mode         (2023 to early 2024)  "Fixed-Time Motion enabled with ZV shaping."
//                one mode for X and Y: M493 S0 standard motion, S1 fixed-time without shaping,
//                S10 ZV, S11 ZVD, S12 EI, S13 2HEI, S14 3HEI, S15 MZV; A/B base frequency X/Y;
//                frequencies "X/A static compensator frequency: 40.00Hz".
//   axis_slash   (2024, per-axis shaping)  "... with X/A axis ZV shaping and with Y/B axis MZV
//                shaping."  S0/S1 fixed-time off/on; X/Y<shaper> (0 none, 1 ZV, 2 ZVD, 3 ZVDD,
//                4 ZVDDD, 5 EI, 6 2HEI, 7 3HEI, 8 MZV); A/B frequency, I/J damping.
//   axis_named   (2024 to 2025)  "... with X axis ZV shaping and with Y axis MZV shaping." (A/B
//                for the steppers of CoreXY/CoreXZ builds); letters as axis_slash; frequencies
//                "X static shaper frequency: 40.00Hz".
//   axis_list    (from 2025, Z and E shaping)  "Fixed-Time Motion enabled (X=ZV ; Y=MZV)".
//                Builds that answer "M493 V" with "FTM V2" take C<shaper> for the axes flagged
//                X/Y/Z/E (none flagged: X and Y) with A<Hz> and I<damping> for the same axes
//                and list unshaped axes as "None"; earlier ones take X/Y/Z/E<shaper> with A/B
//                frequencies, as axis_named.
//
// A build without FT_MOTION answers 'echo:Unknown command: "M493"' (gcode.cpp).

#include <limits>
#include <map>
#include <string>
#include <vector>

namespace tunekit::firmware {

enum class M493Form { none, mode, axis_slash, axis_named, axis_list };

/// One axis's FT_MOTION shaper as reported: Marlin's ftMotionShaper_t code (0 none .. 8 MZV),
/// its report name ("ZV", "2 Hump EI", ...) and its base frequency in Hz (NaN when the report
/// gives none).
struct FtAxisShaper {
  int code = 0;
  std::string name;
  double freq_hz = std::numeric_limits<double>::quiet_NaN();
};

/// What a Marlin machine answered to a bare M493 (and, for the axis_list form, to M493 V).
struct FtMotionReport {
  bool present = false;                        ///< the build has FT_MOTION
  bool active = false;                         ///< "Fixed-Time Motion enabled"
  M493Form form = M493Form::none;              ///< which report form was read
  int version = 1;                             ///< "FTM V<n>" in answer to M493 V (1: no answer)
  std::map<std::string, std::string> shapers;  ///< shaped axis "x"/"y"/"z"/"e" -> name as reported
  std::map<std::string, FtAxisShaper> axes;    ///< every axis the report names, shaped or not
  bool linear_advance = false;                 ///< "Linear Advance enabled. Gain: K"
  double linear_advance_k = 0;
  /// Whether fixed-time motion is active with a shaper on at least one axis.
  bool shaping() const;
};
FtMotionReport parse_m493_report(const std::vector<std::string>& lines);

/// "mode", "axis_slash", "axis_named", "axis_list" (or "none").
std::string to_string(M493Form f);

/// Which letters a build's M493 takes: the form of its report and, for axis_list, the FTM
/// version its M493 V gave (2: the C<shaper> letter, one line per axis).
struct M493Syntax {
  M493Form form = M493Form::axis_named;
  int version = 1;
};
/// The report's syntax (`version` counts only in the axis_list form).
M493Syntax m493_syntax(const FtMotionReport& r);
/// "mode", "axis_slash", "axis_named", "axis_list" or "axis_list_v2" (the list form of FTM V2).
std::string to_string(const M493Syntax& s);
/// The inverse of to_string(M493Syntax) ("none": a report that did not show its form, e.g. one
/// with no axis shaped); InputError for another name.
M493Syntax parse_m493_syntax(const std::string& name);

/// One axis's FT_MOTION shaper to set: axis "x" or "y", Marlin's ftMotionShaper_t code (1 ZV ..
/// 8 MZV), and its base frequency (Hz) and damping ratio as the G-code words should print
/// them (empty: not set).
struct FtShaperWords {
  std::string axis;
  int code = 0;
  std::string freq_hz;
  std::string zeta;
};
/// M493 lines and what the form could not say (one phrase each, e.g. that it has no damping).
struct M493Lines {
  std::vector<std::string> lines;
  std::vector<std::string> left_out;
};
/// The M493 lines that set `axes` in the letters of `syntax`, with "S1" (fixed-time motion on)
/// first when `turn_on` (the mode form's S<mode> always turns it on). mode: one S<mode> for X and
/// Y (X's shaper when they differ), A/B frequency, no damping; axis_slash, axis_named and a
/// version-1 axis_list (and none, the form unknown): X/Y<shaper>, A/B frequency, I/J damping in
/// one line; FTM V2: one line per axis, X|Y C<shaper> A<Hz> I<damping>.
M493Lines m493_set_shapers(const M493Syntax& syntax, const std::vector<FtShaperWords>& axes, bool turn_on);
/// The M493 line that sets fixed-time motion's linear advance gain `k` ("P1 K<k>"), or empty
/// when the form has no such letter (FTM V2).
std::string m493_linear_advance(const M493Syntax& syntax, const std::string& k);

/// The M493 lines that turn every reported FT_MOTION shaper off while fixed-time motion stays
/// on, in the letters of the form that printed `r`; empty when nothing is shaping.
std::vector<std::string> m493_shaping_off(const FtMotionReport& r);
/// The M493 lines that set back the shapers (and their reported frequencies) of `r`.
std::vector<std::string> m493_shaping_restore(const FtMotionReport& r);

}  // namespace tunekit::firmware
