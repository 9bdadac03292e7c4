#pragma once
// Internal to the ring-down analysis (ringdown.cpp): spectral lines of a decay window, the
// choice of the fundamental by its harmonic series over all channels, and the projection of
// the channels in which the fundamental stands highest over the noise.

#include <span>
#include <string>
#include <vector>

namespace tunekit::ident::ringdown_detail {

struct Line {
  double freq_hz = 0;
  double power = 0;  ///< squared amplitude at the peak (summed over channels where so built)
};

/// Local maxima of a power spectrum (bin spacing df) in [lo, hi] Hz, strongest first, with
/// parabolic interpolation of the peak bin.
std::vector<Line> spectral_lines(const std::vector<double>& power, double df, double lo, double hi);

/// The strongest line within a relative tolerance of f, or nullptr.
const Line* line_near(const std::vector<Line>& lines, double f, double tol);

/// The median of a power spectrum over [lo, hi] Hz.
double spectral_floor(const std::vector<double>& power, double df, double lo, double hi);

struct Series {
  Line fundamental;
  std::vector<std::pair<int, Line>> harmonics;  ///< (k, line) for k >= 2 found
  double power = 0;                             ///< the series' summed power
};

struct SeriesChoice {
  Series best;
  Line strongest;
  bool found = false;
};

/// Chooses the fundamental among the clear lines (power >= min_power, >= min_rel of the strongest
/// in power, at or above f_min): the one whose harmonic series carries the most power, a series
/// with harmonics winning over a lone line unless that is over `lone_factor` times stronger.
/// Every candidate's series is collected up to the same top frequency f_max (the lines' band), so
/// the series of f/k holds every line of f's series and a clear sub-harmonic is never outweighed
/// by its own harmonic's series.
/// Weaker lines that can still be a fundamental, for a plucked belt whose fundamental stands
/// lower than its second harmonic where the sensor sits: a line at f/2 of a clear line f
/// with at least `min_power` and `min_rel` of f's power; and a pair of lines g, 2g that both
/// reach `pair_power` (two lines in harmonic ratio, each well over the floor, are rarely noise).
/// A series counts its harmonics down to `pair_power` too. 0 turns a rule off.
struct SubharmonicRule {
  double min_power = 0;
  double min_rel = 0;
  double pair_power = 0;
};
/// Candidates at a frequency in `excluded` (set aside by the caller) are not considered.
SeriesChoice choose_fundamental(const std::vector<Line>& lines, double min_power, double min_rel, double f_min,
                                double f_max, double tol, double lone_factor, const SubharmonicRule& sub = {},
                                const std::vector<double>& excluded = {});

/// Unit weights w (sum of squares 1) of the channels: the direction in which a sinusoid at f_hz
/// stands highest over the noise (channel c's noise RMS noise[c]), from each channel's complex
/// amplitude at f over the window.
std::vector<double> best_projection(const std::vector<std::span<const double>>& windows,
                                    const std::vector<double>& noise, double f_hz, double fs);

}  // namespace tunekit::ident::ringdown_detail
