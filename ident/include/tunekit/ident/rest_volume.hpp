#pragma once
// The melt stored at the first level of a record that starts at rest, measured from its start-up
// transient instead of extrapolated from tau(q) below the flows the record held.
//
// A store of melt V fed by the commanded flow u after the dead time theta and emptied by the
// outflow q obeys dV/dt = u(t - theta) - q(t) whatever its tau(q). Integrated from rest (V = 0,
// q = 0) until it has settled at the first level u1:
//     V(u1) = integral of (u(t - theta) - q(t)) dt,   q = (y - c) / g  (a flow sensor, y = g q + c)
// the area between the delayed feed and the measured outflow. It holds for any dependence of tau
// on the flow, in particular for the melt's Newtonian plateau at the lowest shear rates, where a
// power law of the flow overstates the stored volume (Bird, Armstrong and Hassager, Dynamics of
// polymeric liquids, 1987; the Cross model of the melt's viscosity). The design of the pressure
// advance needs V(Q) = integral of tau over 0..Q (flow_advance.hpp): this is its part below the
// sweep's lowest level, the one no step between levels measures.
//
// A pressure sensor (y = g V + c) reads the stored volume at every level directly; there the
// model's V(q) is measured and nothing is extrapolated, so no area is taken.
//
// Uncertainty: the sensor noise summed over the window (the model's residual standard deviation,
// widened by its variance factor for correlated residuals) and the model's theta, g and c (their
// covariance from the whole-record fit; the area is linear in c and theta, and in 1/g).

#include <optional>
#include <span>
#include <string>

#include <nlohmann/json.hpp>

#include "tunekit/fitting/fit_result.hpp"

namespace tunekit::ident {

struct WholeRecordModel;  // liquefier_record.hpp

struct RestVolume {
  double input = fitting::kNaN;  ///< the first level u1 (the record's input unit)
  double value = fitting::kNaN;  ///< V(u1), input unit s (mm of filament for a feed, mm^3 for a flow)
  double std_error = fitting::kNaN;
  double ci95_lo = fitting::kNaN, ci95_hi = fitting::kNaN;
  double window_begin_s = fitting::kNaN, window_end_s = fitting::kNaN;  ///< record time integrated over
  std::size_t samples = 0;
};

/// The stored volume at the record's first level from its start-up transient, or nullopt with the
/// reason in `why` (may be null): a pressure sensor (it reads V itself), no commanded feed track
/// (a step known only to a sample interval moves the area by up to u1 times that interval), a
/// feed already on when the track begins, a record that does not start at rest, or a first level
/// too short to settle within it (theta + the model's V(u1)/u1 + 10 tau(u1)). The interval sums
/// the noise over the window: the model's residual noise, and up to the first sample at 80 % of
/// u1 that of the samples at rest when it has at least 20 (a start measured less precisely than
/// the rest of the record, as a camera's thin bead).
std::optional<RestVolume> measure_rest_volume(std::span<const double> t, std::span<const double> y,
                                              const WholeRecordModel& m, std::string* why = nullptr);

/// {input, value, stderr, ci95, window_s, samples, basis}; {measured: false, why} without one.
nlohmann::json to_json(const std::optional<RestVolume>& v, const std::string& why);

}  // namespace tunekit::ident
