#pragma once
// The commanded feed as a track: the extruder's planned motion as breakpoints (time, feed),
// linear between them (a planner's moves accelerate at a constant rate, so its velocity is
// piecewise linear); two points at one instant make a step. A load-cell record logs each
// sample's mean feed over its share of the time axis (from halfway to the previous sample to
// halfway to the next), which keeps the fed length but not where in the window the feed changed:
// at 200 Hz a stop and restart between two extrude-only moves (Klipper's, 2-8 ms) fills one or two
// windows, and a model driven by the window means misplaces the step by up to half a window. The
// track places it exactly; its clock (seconds from the first recorded move's start) is brought
// onto the record's by the offset that makes the track's window means match the logged ones.

#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace tunekit::ident {

/// Breakpoints of the commanded feed: t (s, non-decreasing), u (input unit, >= 0).
struct FeedTrack {
  std::vector<double> t, u;
  bool empty() const { return t.empty(); }
};

/// The track as CSV text: "time (s),feed (mm/s)", one breakpoint per row.
std::string feed_track_csv(const FeedTrack& track);

/// Reads a track written by feed_track_csv (or by hand: two numeric columns, time then feed).
/// InputError naming the file and line for a malformed row, a time that decreases, a negative or
/// non-finite value, or fewer than two rows.
FeedTrack read_feed_track_csv(const std::string& path);
/// The same of the file's text already read; `path` locates the errors.
FeedTrack parse_feed_track_csv(std::string_view text, const std::string& path);

/// The window edges of samples at times t (at least two): halfway between time stamps, half an
/// interval beyond the first and the last (how a recorder shares the time axis among its samples).
std::vector<double> sample_window_edges(std::span<const double> t);

/// The track's integral from its first breakpoint to x (input unit s): the length fed.
double feed_track_integral(const FeedTrack& track, double x);

struct FeedTrackAlignment {
  double offset_s = 0;  ///< record time = track time + offset_s (the whole record's)
  /// The offset refined where the record shows the feed change (s), at these record times (s):
  /// linear between them, held beyond. A clock that drifts against the planner's (a sensor's own
  /// oscillator; a simulator's step grid) moves it by tens of microseconds over a record.
  std::vector<double> local_t, local_offset_s;
  double rms_mismatch = 0;  ///< rms of (the track's window means - the logged feed), input unit
  double feed_scale = 0;    ///< the largest logged feed, input unit
  bool matches = false;     ///< rms_mismatch within kFeedTrackMismatch of feed_scale
  FeedTrack aligned;        ///< the track on the record's clock
};

/// A track matches a record when its window means differ from the logged feed by at most this
/// share of the largest feed (rms). Both describe the same commanded motion: the logged means
/// carry five decimals and the firmware's own rounding of a move's speed, far below 1 %; a
/// track of another run, or of a planner that ran the moves differently, misses by tens of %.
inline constexpr double kFeedTrackMismatch = 0.01;
/// Samples in a stretch aligned on its own: a second at 200 Hz, short against a drift of the
/// clocks, long enough to hold a step of a flow sweep in one of three stretches.
inline constexpr std::size_t kFeedTrackSegment = 200;

/// The offset that brings the track onto the record (t, u: the samples' time stamps and their
/// window-mean feeds): started where half the fed length is reached on both, then refined by
/// least squares on the window means over +-4 sample intervals; then, in each stretch of
/// kFeedTrackSegment samples in which the track's feed changes, refined again over +-2 sample
/// intervals for that stretch alone. InputError when the record or the track is too short or
/// feeds nothing.
FeedTrackAlignment align_feed_track(const FeedTrack& track, std::span<const double> t, std::span<const double> u);

}  // namespace tunekit::ident
