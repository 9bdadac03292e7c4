// The first-order step model driven by a commanded input track (StepRecord::input_t, input_u):
// the planner's feed on its own instants, linear between breakpoints, which places a stop between
// two moves where it happened instead of anywhere within the sample window that logged its mean.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/interpolate.hpp"
#include "first_order_detail.hpp"

namespace tunekit::fitting {

namespace {

// Where the first sample's window begins (s): half an interval before it, as a recorder shares
// the time axis among its samples; the model rests settled until its input reaches this instant.
double input_begin(const StepRecord& r) { return r.t.size() < 2 ? r.t.front() : r.t.front() - 0.5 * (r.t[1] - r.t[0]); }

}  // namespace

bool follows_input(const StepRecord& r) { return !r.input_t.empty() || !r.u.empty(); }

void set_input_track(StepRecord& r, std::span<const double> t, std::span<const double> u) {
  if (t.empty() || t.size() != u.size())
    throw InputError(
        fmt::format("an input track needs as many values as instants, at least one ({} and {})", t.size(), u.size()));
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (!std::isfinite(t[i]) || !std::isfinite(u[i])) throw InputError("an input track holds NaN or infinity");
    if (i > 0 && t[i] < t[i - 1])
      throw InputError(fmt::format("an input track's instants decrease ({} s after {} s)", t[i], t[i - 1]));
  }
  r.input_t.clear();
  r.input_u.clear();
  if (r.t.empty()) return;
  const double from = input_begin(r), to = r.t.back();
  r.input_t.push_back(from);
  r.input_u.push_back(interp_linear(t, u, from));  // the value going on from there (a jump's later one)
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (!(t[i] > from && t[i] < to)) continue;
    r.input_t.push_back(t[i]);
    r.input_u.push_back(u[i]);
  }
  if (to > from) {
    r.input_t.push_back(to);
    r.input_u.push_back(interp_linear(t, u, to));
  }
}

namespace first_order_detail {

// dx/ds = (u(s) - x) / tau with u linear between the track's breakpoints, sampled at
// s = t - theta, exact: across a stretch d over which the input runs from a with slope g,
//   x <- a + g (d - tau) + (x - a + g tau) e,   e = exp(-d / tau),
// and its sensitivity w = dx/dtau <- (w + g) e - g + (x - a + g tau) e d / tau^2. Before the
// first sample's window begins the state rests at the input there, x0; dx/dtheta = -(u(s) - x) / tau.
void track_model_points(const StepRecord& r, double K, double tau, double theta, double y0,
                        std::vector<StepModelPoint>& out) {
  const std::vector<double>& bt = r.input_t;
  const std::vector<double>& bu = r.input_u;
  const std::size_t n = r.t.size(), m = bt.size();
  out.resize(n);
  const double s0 = bt.front(), x0 = bu.front();
  double x = x0, w = 0, s_cur = s0;
  // The breakpoint that ends the piece s_cur lies in (m: held beyond the last).
  std::size_t k = 1;
  auto input_at = [&](double s) {  // on the piece ending at breakpoint k
    if (k >= m) return bu.back();
    return bu[k - 1] + (bu[k] - bu[k - 1]) * (s - bt[k - 1]) / (bt[k] - bt[k - 1]);
  };
  auto advance = [&](double to) {  // along the piece ending at breakpoint k, to <= bt[k]
    const double d = to - s_cur;
    if (!(d > 0)) return;
    const double a = input_at(s_cur), g = k >= m ? 0.0 : (bu[k] - bu[k - 1]) / (bt[k] - bt[k - 1]);
    const double e = std::exp(-d / tau), c = x - a + g * tau;
    w = (w + g) * e - g + c * e * d / (tau * tau);
    x = a + g * (d - tau) + c * e;
    s_cur = to;
  };
  for (std::size_t i = 0; i < n; ++i) {
    const double s = r.t[i] - theta;
    if (s <= s0) {
      out[i] = {y0, 0, 0, 0};
      continue;
    }
    for (; k < m && bt[k] <= s; ++k) advance(bt[k]);  // pieces of zero length (jumps) are skipped
    advance(s);
    out[i] = {y0 + K * (x - x0), x - x0, K * w, -K * (input_at(s) - x) / tau};
  }
}

}  // namespace first_order_detail

}  // namespace tunekit::fitting
