#pragma once
// Piecewise-linear interpolation of a table (xs, ys) over increasing xs: the one definition the
// spectra, the pressure- and flow-advance tables and resampling use.

#include <span>
#include <vector>

namespace tunekit::fitting {

/// y at x on the polyline through (xs[i], ys[i]); xs increasing, xs and ys of one size, at
/// least one point. Outside [xs.front(), xs.back()] the end value is held (no extrapolation).
/// At a knot the knot's own y is returned exactly.
double interp_linear(std::span<const double> xs, std::span<const double> ys, double x);

/// interp_linear at every point of xq.
std::vector<double> interp_linear(std::span<const double> xs, std::span<const double> ys, std::span<const double> xq);

}  // namespace tunekit::fitting
