// Output-error fit of an axis' modes against its commanded motion (axis_response_fit.hpp).
#include "tunekit/ident/axis_response_fit.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <future>
#include <limits>
#include <numbers>
#include <span>
#include <string>
#include <thread>

#include <Eigen/Dense>
#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/dense_solvers.hpp"
#include "tunekit/fitting/least_squares.hpp"
#include "tunekit/fitting/levenberg_marquardt.hpp"
#include "tunekit/fitting/stats.hpp"
#include "tunekit/ident/base_excited_mode.hpp"

namespace tunekit::ident {
namespace axis_fit {

/// The commanded acceleration between two samples, piece by piece (fixed for the fit).
struct Sub {
  double h_s, a0, jerk;
};

/// The record's time axis cut at every piece boundary: subs[sample_end[i-1], sample_end[i]) run
/// from sample i-1 to sample i; whole[i] when one piece covers that whole interval (the mode's
/// step of one sample interval then applies).
struct Schedule {
  double dt_s = 0;
  std::vector<Sub> subs;
  std::vector<std::size_t> sample_end;
  std::vector<char> whole;
  std::vector<double> accel_at;  ///< the commanded acceleration at each sample
  std::size_t pieces_used = 0;
};

}  // namespace axis_fit

/// The samples the fit models and the motion on their clock.
struct AxisResponseInput::Data {
  std::vector<double> y;  ///< the channel from the first piece of motion that starts within the record
  axis_fit::Schedule sched;
};

namespace {

using axis_fit::Schedule;
using axis_fit::Sub;

/// Parameters per mode: frequency, damping ratio, gain, deflection and its rate at the first sample.
constexpr std::size_t kParamsPerMode = 5;

double accel_of(const AccelPiece& p, double t) { return p.accel_mm_s2 + p.jerk_mm_s3 * (t - p.t0_s); }

Schedule make_schedule(const std::vector<AccelPiece>& motion, double t0, double dt, std::size_t n) {
  Schedule s;
  s.dt_s = dt;
  s.sample_end.assign(n, 0);
  s.whole.assign(n, 0);
  s.accel_at.assign(n, 0.0);
  // One piece per sample interval and one more per boundary within it, at most: a piece of
  // motion has two boundaries (its start and its end, which is not the next piece's start where
  // the motion pauses). Reserved once, the pieces are not copied (and fresh pages faulted in for
  // the copy) when the vector would grow: with one boundary per piece reserved, a simulated axis
  // sweep's 146k samples and 28k pieces outgrew it, and its copy was an eighth of the fit's page
  // faults. Pages reserved and never written cost nothing.
  const double t_end = t0 + static_cast<double>(n - 1) * dt;
  const auto first = std::partition_point(motion.begin(), motion.end(),
                                          [t0](const AccelPiece& p) { return p.t0_s + p.duration_s <= t0; });
  const auto last = std::partition_point(first, motion.end(), [t_end](const AccelPiece& p) { return p.t0_s < t_end; });
  s.subs.reserve(n + 2 * static_cast<std::size_t>(last - first));
  std::size_t c = 0;
  auto skip_ended = [&](double t) {
    while (c < motion.size() && motion[c].t0_s + motion[c].duration_s <= t) ++c;
  };
  skip_ended(t0);
  if (c < motion.size() && motion[c].t0_s <= t0) s.accel_at[0] = accel_of(motion[c], t0);
  const std::size_t first_piece = c;
  for (std::size_t i = 1; i < n; ++i) {
    const double ta = t0 + static_cast<double>(i - 1) * dt, tb = t0 + static_cast<double>(i) * dt;
    const std::size_t begin = s.subs.size();
    double t = ta;
    while (t < tb) {
      skip_ended(t);
      if (c < motion.size() && motion[c].t0_s <= t) {
        const double to = std::min(tb, motion[c].t0_s + motion[c].duration_s);
        s.subs.push_back({to - t, accel_of(motion[c], t), motion[c].jerk_mm_s3});
        t = to;
      } else {
        const double to = c < motion.size() ? std::min(tb, motion[c].t0_s) : tb;
        s.subs.push_back({to - t, 0.0, 0.0});
        t = to;
      }
    }
    s.sample_end[i] = s.subs.size();
    s.whole[i] = s.subs.size() - begin == 1;
    skip_ended(tb);
    if (c < motion.size() && motion[c].t0_s <= tb) s.accel_at[i] = accel_of(motion[c], tb);
  }
  s.pieces_used = c - first_piece;
  return s;
}

/// One mode's relative acceleration z''_i at every sample, its state started at x0 on the first
/// sample (rel); when d_z0 and d_v0 are not null, also that of its free response to a unit
/// deflection and a unit rate there: the response is affine in x0, so these are its derivatives
/// in z0 and v0.
void mode_response(const Schedule& s, double freq_hz, double zeta, ModeState x0, double* rel, double* d_z0,
                   double* d_v0) {
  const std::size_t n = s.accel_at.size();
  const BaseExcitedMode mode(freq_hz, zeta);
  const ModeStep step = mode.step(s.dt_s);
  const bool basis = d_z0 != nullptr && d_v0 != nullptr;
  ModeState x = x0, e1{1, 0}, e2{0, 1};
  auto record = [&](std::size_t i) {
    rel[i] = mode.relative_accel(x, s.accel_at[i]);
    if (basis) d_z0[i] = mode.relative_accel(e1, 0), d_v0[i] = mode.relative_accel(e2, 0);
  };
  record(0);
  for (std::size_t i = 1; i < n; ++i) {
    if (s.whole[i]) {
      const Sub& u = s.subs[s.sample_end[i - 1]];
      x = BaseExcitedMode::apply(step, x, u.a0, u.jerk);
      if (basis) e1 = BaseExcitedMode::apply(step, e1, 0, 0), e2 = BaseExcitedMode::apply(step, e2, 0, 0);
    } else {
      for (std::size_t j = s.sample_end[i - 1]; j < s.sample_end[i]; ++j) {
        double phi[2][2];
        mode.free_map(s.subs[j].h_s, phi);
        x = mode.advance(x, s.subs[j].h_s, s.subs[j].a0, s.subs[j].jerk, phi);
        if (basis) e1 = mode.advance(e1, s.subs[j].h_s, 0, 0, phi), e2 = mode.advance(e2, s.subs[j].h_s, 0, 0, phi);
      }
    }
    record(i);
  }
}

/// The record's model for parameters p (see axis_response_fit.hpp): y_i = a_i + sum_k g_k z_k''
/// + offset. `rel` is scratch of the record's length.
void model(const Schedule& s, std::size_t modes, const double* p, std::vector<double>& y, std::vector<double>& rel) {
  const std::size_t n = s.accel_at.size();
  const double offset = p[kParamsPerMode * modes];
  for (std::size_t i = 0; i < n; ++i) y[i] = s.accel_at[i] + offset;
  for (std::size_t k = 0; k < modes; ++k) {
    const double* q = p + kParamsPerMode * k;
    mode_response(s, q[0], q[1], {q[3], q[4]}, rel.data(), nullptr, nullptr);
    const double gain = q[2];
    for (std::size_t i = 0; i < n; ++i) y[i] += gain * rel[i];
  }
}

/// Damping ratio below which a mode's frequency and damping derivatives are propagated exactly
/// (mode_sensitivities: the under-damped transition); closer to critical damping its form divides
/// by sqrt(1 - zeta^2), and the Jacobian's columns are differenced instead.
constexpr double kSensitivityMaxZeta = 0.999;

/// What the transitions and steps of one under-damped mode share, for its w (rad/s) and zeta:
/// computed once per mode and evaluation, not per step (a square root and two divisions), by the
/// same expressions as before, so that every step is rounded as it was.
/// dk, dc, dsg and dwd are the derivatives of k = w^2, c = 2 zeta w, sg = zeta w and
/// wd = w sqrt(1 - zeta^2) in w (index 0) and zeta (index 1).
struct ModeConstants {
  double w, zeta, k, c, inv_k, inv_k2, sg, r1, wd;
  double dk[2], dc[2], dsg[2], dwd[2];
};

ModeConstants mode_constants(double w, double zeta) {
  ModeConstants m;
  m.w = w, m.zeta = zeta, m.k = w * w, m.c = 2 * zeta * w;
  m.inv_k = 1 / m.k, m.inv_k2 = m.inv_k * m.inv_k;
  m.sg = zeta * w, m.r1 = std::sqrt(1 - zeta * zeta), m.wd = w * m.r1;
  m.dk[0] = 2 * w, m.dk[1] = 0;
  m.dc[0] = 2 * zeta, m.dc[1] = 2 * w;
  m.dsg[0] = zeta, m.dsg[1] = w;
  m.dwd[0] = m.r1, m.dwd[1] = -w * zeta / m.r1;
  return m;
}

/// The free transition over h of an under-damped mode (BaseExcitedMode::free_map's) and its
/// derivatives d[p] in w (rad/s, p = 0) and zeta (p = 1): the product rule through the decay
/// exp(-zeta w h) and the damped oscillation's cos and sin(w sqrt(1 - zeta^2) h).
struct Transition {
  double phi[2][2];
  double d[2][2][2];
};

Transition transition(const ModeConstants& m, double h) {
  Transition t;
  const double k = m.k, sg = m.sg, wd = m.wd;
  const double D = std::exp(-sg * h), C = std::cos(wd * h), S = std::sin(wd * h), q = S / wd;
  t.phi[0][0] = D * (C + sg * q);
  t.phi[0][1] = D * q;
  t.phi[1][0] = -k * D * q;
  t.phi[1][1] = D * (C - sg * q);
  for (int p = 0; p < 2; ++p) {
    const double dsg = m.dsg[p], dwd = m.dwd[p], dk = m.dk[p];
    const double dD = -h * D * dsg, dC = -S * h * dwd, dq = dwd * (C * h - q) / wd;
    t.d[p][0][0] = dD * (C + sg * q) + D * (dC + dsg * q + sg * dq);
    t.d[p][0][1] = dD * q + D * dq;
    t.d[p][1][0] = -(dk * D * q + k * t.d[p][0][1]);
    t.d[p][1][1] = dD * (C - sg * q) + D * (dC - dsg * q - sg * dq);
  }
  return t;
}

/// A mode's state, its derivatives in w and zeta, and its free responses to a unit deflection
/// and a unit rate at the first sample; `free_decayed` once those are taken as 0 for good.
struct SensitivityState {
  double z = 0, v = 0;
  double sz[2] = {0, 0}, sv[2] = {0, 0};
  double e1z = 1, e1v = 0, e2z = 0, e2v = 1;
  bool free_decayed = false;
};

/// One exact step of h under a(s) = a0 + j s (BaseExcitedMode::advance: the free transition of
/// the state less the particular solution z_p = -(a0 + j s)/k + c j/k^2, k = w^2, c = 2 zeta w)
/// with the derivatives carried through it, the divisions by k of the mode's constants.
void sensitivity_step(SensitivityState& x, const Transition& t, const ModeConstants& m, double h, double a0, double j) {
  const double c = m.c, inv_k = m.inv_k, inv_k2 = m.inv_k2;
  const double zp0 = -a0 * inv_k + c * j * inv_k2, vp = -j * inv_k, zp1 = zp0 - j * h * inv_k;
  const double ez = x.z - zp0, ev = x.v - vp;
  for (int p = 0; p < 2; ++p) {
    const double dk = m.dk[p], dc = m.dc[p];
    const double dzp0 = (a0 * dk + j * dc - 2 * c * j * dk * inv_k) * inv_k2, dvp = j * dk * inv_k2;
    const double dzp1 = dzp0 + j * h * dk * inv_k2;
    const double dez = x.sz[p] - dzp0, dev = x.sv[p] - dvp;
    const double nz = t.d[p][0][0] * ez + t.d[p][0][1] * ev + t.phi[0][0] * dez + t.phi[0][1] * dev + dzp1;
    const double nv = t.d[p][1][0] * ez + t.d[p][1][1] * ev + t.phi[1][0] * dez + t.phi[1][1] * dev + dvp;
    x.sz[p] = nz, x.sv[p] = nv;
  }
  x.z = t.phi[0][0] * ez + t.phi[0][1] * ev + zp1;
  x.v = t.phi[1][0] * ez + t.phi[1][1] * ev + vp;
  if (x.free_decayed) return;  // zeros stay zeros
  const double e1z = t.phi[0][0] * x.e1z + t.phi[0][1] * x.e1v, e2z = t.phi[0][0] * x.e2z + t.phi[0][1] * x.e2v;
  x.e1v = t.phi[1][0] * x.e1z + t.phi[1][1] * x.e1v, x.e2v = t.phi[1][0] * x.e2z + t.phi[1][1] * x.e2v;
  x.e1z = e1z, x.e2z = e2z;
}

/// Columns of one under-damped mode's relative acceleration z'' = -c v - k z - a at every sample
/// (forward sensitivities, exact for the model), a block of samples at a time: out[0][i] its
/// derivative in the frequency (Hz), out[1][i] in zeta, out[2][i] the value itself, out[3][i] and
/// out[4][i] the derivatives in the first deflection and rate.
class ModeSensitivities {
 public:
  ModeSensitivities(const Schedule& s, double freq_hz, double zeta, ModeState x0)
      : s_(s), m_(mode_constants(2 * std::numbers::pi * freq_hz, zeta)), whole_(transition(m_, s.dt_s)) {
    x_.z = x0.z_mm, x_.v = x0.v_mm_s;
  }

  /// The same mode with next() going on from sample `from`: started from rest at sample `rest`
  /// (what the motion does from there on), carried to sample from - 1, where the response to the
  /// first state x0 and the free responses to a unit first state are added, exactly (the free
  /// transition over from - 1 sample intervals and its derivatives). What the motion before `rest`
  /// left ringing is left out: the caller chooses `rest` where that has decayed below the rounding
  /// of the propagation (warm_up_samples).
  ModeSensitivities(const Schedule& s, double freq_hz, double zeta, ModeState x0, std::size_t rest, std::size_t from)
      : ModeSensitivities(s, freq_hz, zeta, ModeState{0, 0}) {
    x_.e1z = x_.e2v = 0;
    x_.free_decayed = true;
    for (std::size_t i = rest + 1; i < from; ++i) step_to(i);
    const Transition t = transition(m_, static_cast<double>(from - 1) * s.dt_s);
    const double z0 = x0.z_mm, v0 = x0.v_mm_s;
    x_.z += t.phi[0][0] * z0 + t.phi[0][1] * v0;
    x_.v += t.phi[1][0] * z0 + t.phi[1][1] * v0;
    for (int p = 0; p < 2; ++p) {
      x_.sz[p] += t.d[p][0][0] * z0 + t.d[p][0][1] * v0;
      x_.sv[p] += t.d[p][1][0] * z0 + t.d[p][1][1] * v0;
    }
    x_.e1z = t.phi[0][0], x_.e1v = t.phi[1][0], x_.e2z = t.phi[0][1], x_.e2v = t.phi[1][1];
    x_.free_decayed = false;
    next_ = from;
  }

  /// The samples from where the last call ended (the first sample at first) up to `end`, into
  /// out[c][0 ..].
  void next(std::size_t end, double* const out[5]) {
    const double k = m_.k, c = m_.c;
    for (std::size_t o = 0; next_ < end; ++next_, ++o) {
      const std::size_t i = next_;
      if (i > 0 && (step_to(i), !x_.free_decayed)) flush_decayed(i);
      for (int p = 0; p < 2; ++p) out[p][o] = -m_.dc[p] * x_.v - m_.dk[p] * x_.z - c * x_.sv[p] - k * x_.sz[p];
      out[0][o] *= 2 * std::numbers::pi;  // dw / df
      out[2][o] = -c * x_.v - k * x_.z - s_.accel_at[i];
      out[3][o] = -c * x_.e1v - k * x_.e1z;
      out[4][o] = -c * x_.e2v - k * x_.e2z;
    }
  }

  /// The first sample from which out[3] and out[4] are 0 (the free responses have decayed), as
  /// far as next() has gone; the largest size_t before.
  std::size_t free_zero_from() const { return free_zero_from_; }

 private:
  // The free responses to the first state decay geometrically; once below kDecayed they are
  // taken as 0 (and neither propagated nor multiplied any more), long before they and their
  // products in J'J would reach the subnormal range, where every operation on them costs a
  // hundred or more cycles. A mode at 48 Hz with zeta 0.08 decays below 1e-60 of its unit start
  // within 6 s. What they would still add to a sum of J'J or J'r is then some 40 orders of
  // magnitude below that sum's rounding unit: the sums come out the same to the last bit.
  static constexpr double kDecayed = 1e-60;
  void flush_decayed(std::size_t i) {
    if (std::abs(x_.e1z) < kDecayed && std::abs(x_.e1v) < kDecayed) x_.e1z = x_.e1v = 0;
    if (std::abs(x_.e2z) < kDecayed && std::abs(x_.e2v) < kDecayed) x_.e2z = x_.e2v = 0;
    if (x_.e1z == 0 && x_.e1v == 0 && x_.e2z == 0 && x_.e2v == 0) x_.free_decayed = true, free_zero_from_ = i;
  }

  // From sample i - 1 to sample i.
  void step_to(std::size_t i) {
    if (s_.whole[i]) {
      const Sub& u = s_.subs[s_.sample_end[i - 1]];
      sensitivity_step(x_, whole_, m_, s_.dt_s, u.a0, u.jerk);
      return;
    }
    for (std::size_t j = s_.sample_end[i - 1]; j < s_.sample_end[i]; ++j)
      if (s_.subs[j].h_s > 0)
        sensitivity_step(x_, transition(m_, s_.subs[j].h_s), m_, s_.subs[j].h_s, s_.subs[j].a0, s_.subs[j].jerk);
  }

  const Schedule& s_;
  ModeConstants m_;
  Transition whole_;
  SensitivityState x_;
  std::size_t next_ = 0;
  std::size_t free_zero_from_ = std::numeric_limits<std::size_t>::max();
};

/// Samples after which what a mode's state was has decayed below 2^-64 of itself in the state and
/// its derivatives in w and zeta (exp(-zeta w t) (1 + w t), the derivatives' secular factor), at
/// sample interval dt: beyond the rounding (2^-53) of the propagation itself.
std::size_t warm_up_samples(double freq_hz, double zeta, double dt) {
  const double w = 2 * std::numbers::pi * freq_hz, a = zeta * w, digits = 64 * std::numbers::ln2;
  double t = digits / a;
  for (int it = 0; it < 8; ++it) t = (digits + std::log1p(w * t)) / a;
  return static_cast<std::size_t>(std::ceil(t / dt)) + 1;
}

/// Are the modes' frequencies and damping ratios in the model's domain?
bool in_domain(const double* p, std::size_t modes) {
  for (std::size_t k = 0; k < modes; ++k)
    if (!(p[kParamsPerMode * k] > 0) || !(p[kParamsPerMode * k + 1] > 0)) return false;
  return true;
}

/// Rows of the Jacobian taken together when J'J is summed: their columns stay in the first-level
/// cache while every pair of columns is multiplied (a general matrix product of the 6 x 100k-odd
/// transpose with the 100k-odd x 6 Jacobian took several times longer than the model's evaluation).
constexpr Eigen::Index kRowBlock = 512;

/// Records shorter than this many samples are summed on one thread.
constexpr std::size_t kMinSplitSamples = 16 * static_cast<std::size_t>(kRowBlock);

/// The normal equations J'J and J'r of the residuals y - model, a block of kRowBlock samples at a
/// time: each mode's columns for the block are propagated (ModeSensitivities) and multiplied while
/// they are in the first-level cache, so the samples x parameters Jacobian is never stored. The
/// gain, the first state and the offset enter the model linearly; a mode's frequency and damping
/// ratio by forward sensitivities, or, for a mode near critical damping, by central differences of
/// that mode's response alone with the step of solve_least_squares' numeric Jacobian (1e-6 of the
/// value), computed for the whole record first.
/// On a machine with two or more cores the record is cut in two halves summed on two threads: the
/// second half's modes start from rest some samples before it (warm_up_samples: the damped modes
/// forget their earlier state below the rounding) plus the exact response to the first state.
/// The sums then differ from those on one thread only in the rounding of their order. A mode too
/// lightly damped to forget its state within a quarter of the record keeps the fit on one thread.
class RecordEquations {
 public:
  RecordEquations(const Schedule& s, std::size_t modes, const std::vector<double>& y)
      : s_(s), modes_(modes), y_(y), differenced_(modes) {
    for (auto& w : scratch_) {
      w.block.resize(kRowBlock, static_cast<Eigen::Index>(modes * kParamsPerMode + 1));
      w.raw.resize(kParamsPerMode * static_cast<std::size_t>(kRowBlock));
      w.model.resize(static_cast<std::size_t>(kRowBlock));
      w.r.resize(kRowBlock);
      w.zero.resize(modes * kParamsPerMode + 1);
    }
  }

  /// J'J into N and J'r into g at p; returns the residual sum of squares (HUGE_VAL outside the
  /// model's domain), the residuals into `residuals` when it is not empty.
  double operator()(const double* p, Eigen::MatrixXd& N, Eigen::VectorXd& g, std::span<double> residuals) {
    if (!in_domain(p, modes_)) return HUGE_VAL;
    const Eigen::Index k = scratch_[0].block.cols();
    N.setZero(k, k);
    g.setZero(k);
    for (std::size_t m = 0; m < modes_; ++m)
      if (const double* q = p + kParamsPerMode * m; !(q[1] < kSensitivityMaxZeta))
        differenced_columns(q, differenced_[m]);
    const std::size_t n = y_.size(), split = split_at(p);
    if (split == n) {
      const double rss = sum_range(p, props_from(p, 0, 0), 0, n, scratch_[0], N, g, residuals);
      N.triangularView<Eigen::StrictlyUpper>() = N.transpose();
      return rss;
    }
    Eigen::MatrixXd N2 = Eigen::MatrixXd::Zero(k, k);
    Eigen::VectorXd g2 = Eigen::VectorXd::Zero(k);
    double rss2 = 0;
    std::thread second([&] {
      rss2 = sum_range(p, props_from(p, split - warm_up(p), split), split, n, scratch_[1], N2, g2, residuals);
    });
    const double rss = sum_range(p, props_from(p, 0, 0), 0, split, scratch_[0], N, g, residuals);
    second.join();
    N += N2;
    g += g2;
    N.triangularView<Eigen::StrictlyUpper>() = N.transpose();
    return rss + rss2;
  }

 private:
  // What one thread's sums use.
  struct Scratch {
    Eigen::MatrixXd block;  // kRowBlock x parameters, column-major
    std::vector<double> raw, model;
    Eigen::VectorXd r;
    std::vector<char> zero;  // per column: 0 throughout the block
  };

  // The samples the second half's modes start from rest before it: the longest of the modes'.
  std::size_t warm_up(const double* p) const {
    std::size_t w = 0;
    for (std::size_t m = 0; m < modes_; ++m)
      if (const double* q = p + kParamsPerMode * m; q[1] < kSensitivityMaxZeta)
        w = std::max(w, warm_up_samples(q[0], q[1], s_.dt_s));
    return w;
  }

  // Where the second half starts (a block boundary, the halves' work balanced), or n: one thread.
  std::size_t split_at(const double* p) const {
    const std::size_t n = y_.size(), B = static_cast<std::size_t>(kRowBlock);
    if (n < kMinSplitSamples || std::thread::hardware_concurrency() < 2) return n;
    const std::size_t w = warm_up(p);
    if (w > n / 4) return n;
    return std::max((n + w) / 2 / B * B, w + 1);
  }

  // The under-damped modes' propagations from sample `from` (started from rest at `rest`, or at
  // the first state for from = 0).
  std::vector<ModeSensitivities> props_from(const double* p, std::size_t rest, std::size_t from) const {
    std::vector<ModeSensitivities> props;
    props.reserve(modes_);
    for (std::size_t m = 0; m < modes_; ++m) {
      const double* q = p + kParamsPerMode * m;
      if (!(q[1] < kSensitivityMaxZeta)) continue;
      if (from == 0) props.emplace_back(s_, q[0], q[1], ModeState{q[3], q[4]});
      else props.emplace_back(s_, q[0], q[1], ModeState{q[3], q[4]}, rest, from);
    }
    return props;
  }

  // The samples [from, to) added to N's lower triangle and g; returns their residual sum of squares.
  double sum_range(const double* p, std::vector<ModeSensitivities> props, std::size_t from, std::size_t to, Scratch& w,
                   Eigen::MatrixXd& N, Eigen::VectorXd& g, std::span<double> residuals) {
    const Eigen::Index k = w.block.cols();
    double rss = 0;
    for (std::size_t b = from; b < to; b += static_cast<std::size_t>(kRowBlock)) {
      const std::size_t len = std::min(static_cast<std::size_t>(kRowBlock), to - b);
      const double offset = p[kParamsPerMode * modes_];
      for (std::size_t i = 0; i < len; ++i) w.model[i] = s_.accel_at[b + i] + offset;
      std::fill(w.zero.begin(), w.zero.end(), 0);
      for (std::size_t m = 0, sens = 0; m < modes_; ++m) {
        const double* q = p + kParamsPerMode * m;
        if (q[1] < kSensitivityMaxZeta) {
          sensitivity_block(w, props[sens], q[2], static_cast<Eigen::Index>(kParamsPerMode * m), b, len);
          // The block's columns in the first state are 0 once the free responses have decayed:
          // their products add nothing to the sums.
          if (props[sens++].free_zero_from() <= b) w.zero[kParamsPerMode * m + 3] = w.zero[kParamsPerMode * m + 4] = 1;
        } else {
          differenced_block(w, differenced_[m], q[2], static_cast<Eigen::Index>(kParamsPerMode * m), b, len);
        }
      }
      const auto L = static_cast<Eigen::Index>(len);
      w.block.col(k - 1).head(L).setConstant(-1);  // the offset
      for (std::size_t i = 0; i < len; ++i) w.r(static_cast<Eigen::Index>(i)) = y_[b + i] - w.model[i];
      if (!residuals.empty()) std::copy(w.r.data(), w.r.data() + L, residuals.begin() + static_cast<std::ptrdiff_t>(b));
      for (Eigen::Index i = 0; i < k; ++i) {
        if (w.zero[static_cast<std::size_t>(i)]) continue;
        const auto ci = w.block.col(i).head(L);
        for (Eigen::Index j = 0; j <= i; ++j)
          if (!w.zero[static_cast<std::size_t>(j)]) N(i, j) += ci.dot(w.block.col(j).head(L));
        g(i) += ci.dot(w.r.head(L));
      }
      rss += w.r.head(L).squaredNorm();
    }
    return rss;
  }

  // The next block of an under-damped mode's columns (from column c) and its share of the model.
  static void sensitivity_block(Scratch& w, ModeSensitivities& prop, double gain, Eigen::Index c, std::size_t b,
                                std::size_t len) {
    const std::size_t B = static_cast<std::size_t>(kRowBlock);
    double* const out[5] = {w.raw.data(), w.raw.data() + B, w.raw.data() + 2 * B, w.raw.data() + 3 * B,
                            w.raw.data() + 4 * B};
    prop.next(b + len, out);
    for (std::size_t i = 0; i < len; ++i) {
      const auto row = static_cast<Eigen::Index>(i);
      w.block(row, c) = -gain * out[0][i];
      w.block(row, c + 1) = -gain * out[1][i];
      w.block(row, c + 2) = -out[2][i];
      w.block(row, c + 3) = -gain * out[3][i];
      w.block(row, c + 4) = -gain * out[4][i];
      w.model[i] += gain * out[2][i];
    }
  }

  // A mode near critical damping: its response and the derivatives in the first state for the
  // whole record (mode_response), and those in the frequency and the damping ratio by central
  // differences: cols = {response(+h) - response(-h) in f and in zeta, value, d/dz0, d/dv0} of
  // the relative acceleration, h the steps.
  struct Differenced {
    std::array<std::vector<double>, 5> cols;
    double h[2] = {0, 0};
  };
  void differenced_columns(const double* q, Differenced& dif) {
    auto& cols = dif.cols;
    for (auto& c : cols) c.resize(y_.size());
    const ModeState x0{q[3], q[4]};
    mode_response(s_, q[0], q[1], x0, cols[2].data(), cols[3].data(), cols[4].data());
    std::vector<double> minus(y_.size());
    for (int d = 0; d < 2; ++d) {
      const double h = 1e-6 * std::max(std::abs(q[d]), 1e-6);
      double qp[2] = {q[0], q[1]}, qm[2] = {q[0], q[1]};
      qp[d] += h;
      qm[d] -= h;
      auto& plus = cols[static_cast<std::size_t>(d)];
      mode_response(s_, qp[0], qp[1], x0, plus.data(), nullptr, nullptr);
      mode_response(s_, qm[0], qm[1], x0, minus.data(), nullptr, nullptr);
      for (std::size_t i = 0; i < y_.size(); ++i) plus[i] -= minus[i];
      dif.h[d] = h;
    }
  }
  static void differenced_block(Scratch& w, const Differenced& dif, double gain, Eigen::Index c, std::size_t b,
                                std::size_t len) {
    const auto& cols = dif.cols;
    for (std::size_t i = 0; i < len; ++i) {
      const auto row = static_cast<Eigen::Index>(i);
      w.block(row, c) = -gain * cols[0][b + i] / (2 * dif.h[0]);
      w.block(row, c + 1) = -gain * cols[1][b + i] / (2 * dif.h[1]);
      w.block(row, c + 2) = -cols[2][b + i];
      w.block(row, c + 3) = -gain * cols[3][b + i];
      w.block(row, c + 4) = -gain * cols[4][b + i];
      w.model[i] += gain * cols[2][b + i];
    }
  }

  const Schedule& s_;
  std::size_t modes_;
  const std::vector<double>& y_;
  std::array<Scratch, 2> scratch_;  // the first half's (or the whole record's) and the second's
  std::vector<Differenced> differenced_;
};

std::vector<fitting::ParamSpec> params_for(const std::vector<fitting::ModeStart>& starts, double max_zeta) {
  std::vector<fitting::ParamSpec> ps;
  for (std::size_t k = 0; k < starts.size(); ++k) {
    const auto idx = std::to_string(k + 1);
    const double f0 = starts[k].freq_hz;
    ps.push_back({"freq_hz_" + idx, "Hz", f0, 0.5 * f0, 1.5 * f0});
    ps.push_back({"zeta_" + idx, "1", std::clamp(starts[k].zeta, 2e-4, max_zeta), 1e-4, max_zeta});
    ps.push_back({"gain_" + idx, "1", 1.0 / static_cast<double>(starts.size())});
    ps.push_back({"z0_mm_" + idx, "mm", 0.0});
    ps.push_back({"v0_mm_s_" + idx, "mm/s", 0.0});
  }
  ps.push_back({"offset_mm_s2", "mm/s^2", 0.0});
  return ps;
}

/// Inflates the intervals by the residuals' correlation and collects the modes.
void finish(AxisResponseFit& out, std::size_t modes, double confidence) {
  fitting::inflate_uncertainty(out.fit, out.variance_inflation, confidence);
  out.modes = fitting::modes_from_params(out.fit.params, modes, kParamsPerMode);
}

/// Below this ratio of the extreme singular values of the Jacobian with unit-scaled columns the
/// parameters are not identifiable: the check of the FOPDT fit's covariance (first_order.cpp,
/// fill_covariance), about a millionth of the rounding that a double's 16 digits allow in J'J.
constexpr double kMinScaledReciprocalCondition = 1e-10;

/// Standard errors, 95 % intervals and the covariance s^2 (J'J)^-1 from the normal matrix at the
/// solution: what ceres::Covariance computes from J, with the rank check on the columns scaled
/// to unit length (so that the units of the parameters do not decide it). FitError when rank
/// deficient.
void set_covariance(fitting::FitResult& f, const Eigen::MatrixXd& JtJ, double confidence) {
  const Eigen::Index k = JtJ.rows();
  Eigen::VectorXd d(k);
  for (Eigen::Index j = 0; j < k; ++j) d(j) = 1.0 / std::sqrt(std::max(JtJ(j, j), 1e-300));
  const Eigen::MatrixXd S = d.asDiagonal() * JtJ * d.asDiagonal();
  const Eigen::VectorXd eigenvalues = fitting::symmetric_eigenvalues(S);
  const double lmin = eigenvalues.minCoeff(), lmax = eigenvalues.maxCoeff();
  if (!(lmax > 0) || !(lmin > 0) || std::sqrt(lmin / lmax) < kMinScaledReciprocalCondition) {
    std::string names;
    for (const auto& p : f.params) names += (names.empty() ? "" : ", ") + p.name;
    throw FitError(f.model + ": parameters not identifiable from these data (the Jacobian of " + names +
                   " is rank deficient); record a longer or richer response, or fix a parameter");
  }
  const Eigen::MatrixXd Sinv = fitting::inverse(S);
  const int dof = f.diagnostics.num_observations - static_cast<int>(k);
  if (dof <= 0) throw FitError(f.model + ": as many parameters as data points; no uncertainty can be estimated");
  const double s2 = f.diagnostics.rss / dof, tq = fitting::t_multiplier(confidence, dof);
  f.covariance.assign(static_cast<std::size_t>(k * k), 0.0);
  for (Eigen::Index i = 0; i < k; ++i)
    for (Eigen::Index j = 0; j < k; ++j)
      f.covariance[static_cast<std::size_t>(i * k + j)] = Sinv(i, j) * d(i) * d(j) * s2;
  for (Eigen::Index j = 0; j < k; ++j) {
    auto& p = f.params[static_cast<std::size_t>(j)];
    p.ci95_method = "wald";
    p.std_error = std::sqrt(f.covariance[static_cast<std::size_t>(j * k + j)]);
    p.ci95_lo = p.value - tq * p.std_error;
    p.ci95_hi = p.value + tq * p.std_error;
    if (!std::isfinite(p.std_error))
      throw FitError(f.model + ": the uncertainty of " + p.name + " is not finite; it is not identifiable");
  }
}

/// The FitResult of a converged solve on the normal equations at p, J'J there: what
/// solve_least_squares reports for the same solution (residual diagnostics, bound warnings, the
/// covariance). `res`: the residuals at p.
fitting::FitResult normal_solve_result(const std::vector<double>& y, const std::vector<double>& res,
                                       const fitting::LsqProblem& prob, const std::vector<double>& p,
                                       const Eigen::MatrixXd& JtJ, const fitting::lm_detail::Confirmed& c,
                                       double confidence) {
  fitting::FitResult f;
  f.model = "axis_output_error";
  f.diagnostics.iterations = c.iterations;
  f.diagnostics.num_parameters = static_cast<int>(p.size());
  f.diagnostics.converged = true;
  f.diagnostics.solver =
      fmt::format("Levenberg-Marquardt on the {}x{} normal equations: {} iterations after the polish, converged",
                  p.size(), p.size(), c.iterations);
  for (double v : p)
    if (!std::isfinite(v)) throw FitError(f.model + ": the solution is not finite (" + f.diagnostics.solver + ")");
  fitting::fill_residual_diagnostics(f, res, y, true);
  for (std::size_t j = 0; j < p.size(); ++j) {
    const auto& ps = prob.params[j];
    fitting::Param q;
    q.name = ps.name;
    q.unit = ps.unit;
    q.value = p[j];
    if (p[j] <= ps.lower || p[j] >= ps.upper)
      f.warnings.push_back(ps.name + " ended on its bound (" + std::to_string(p[j]) + ")");
    f.params.push_back(q);
  }
  set_covariance(f, JtJ, confidence);
  return f;
}

/// Ceres from p, with the numeric Jacobian of the model's residuals (the fit before the solve on
/// the normal equations).
fitting::FitResult ceres_from(const Schedule& sched, std::size_t modes, const std::vector<double>& y,
                              fitting::LsqProblem& prob, const fitting::LsqOptions& lo, const std::vector<double>& p) {
  for (std::size_t j = 0; j < p.size(); ++j) prob.params[j].start = p[j];
  prob.observed = y;  // for solve_least_squares' diagnostics (the normal-equation path needs no copy)
  std::vector<double> m(y.size()), rel(y.size());
  prob.residuals = [&](const double* q, double* r) {
    if (!in_domain(q, modes)) return false;
    model(sched, modes, q, m, rel);
    for (std::size_t i = 0; i < y.size(); ++i) r[i] = y[i] - m[i];
    return true;
  };
  return fitting::solve_least_squares("axis_output_error", prob, lo);
}

/// The fit by Levenberg-Marquardt on the normal equations (levenberg_marquardt.hpp) to Ceres
/// Solver's convergence tests with the tolerances `lo`, as solve_least_squares reports it; the
/// record's 100k-odd rows are never factorised (Ceres' dense QR of the whole Jacobian, its
/// projected line search on the bounded frequencies and damping ratios, which evaluates each
/// trial with its Jacobian, and the SVD of the Jacobian for the covariance cost about six times
/// the model's evaluations). When that does not converge, Ceres takes over from where it ended.
/// The trials of the confirming iterations are costed by the model alone (about a quarter of an
/// evaluation of the normal equations): the last one, which meets a tolerance, is not taken.
/// `residuals`: those at the solution; `variance_factor`: their residual_variance_factor.
fitting::FitResult solve_record(const Schedule& sched, std::size_t modes, const std::vector<double>& y,
                                fitting::LsqProblem& prob, const fitting::LsqOptions& lo,
                                std::vector<double>& residuals, double& variance_factor) {
  const std::size_t k = prob.params.size(), n = y.size();
  std::vector<double> p(k), lower(k), upper(k), m(n), rel(n);
  const std::vector<bool> fixed(k, false);
  for (std::size_t j = 0; j < k; ++j)
    lower[j] = prob.params[j].lower, upper[j] = prob.params[j].upper,
    p[j] = std::clamp(prob.params[j].start, lower[j], upper[j]);
  RecordEquations record_equations(sched, modes, y);
  fitting::lm_detail::ResidualMemo memo(n);
  auto equations = [&](std::span<const double> q, Eigen::MatrixXd& N, Eigen::VectorXd& g) {
    const double c = record_equations(q.data(), N, g, memo.trial());
    memo.evaluated(q, c);
    return c;
  };
  auto cost = [&](std::span<const double> q) {
    if (!in_domain(q.data(), modes)) return HUGE_VAL;
    model(sched, modes, q.data(), m, rel);
    double rss = 0;
    for (std::size_t i = 0; i < n; ++i) rss += (y[i] - m[i]) * (y[i] - m[i]);
    return rss;
  };
  fitting::lm_detail::Equations<Eigen::MatrixXd, Eigen::VectorXd> at;
  at.cost = equations(std::span<const double>(p), at.N, at.g);
  fitting::lm_detail::Confirmed c;
  if (std::isfinite(at.cost)) {
    double lambda = fitting::lm_detail::kInitialDamping;
    const std::span<double> ps(p);
    const std::span<const double> los(lower), his(upper);
    fitting::lm_detail::polish_from(ps, los, his, fixed, equations, at, lambda, true);
    c = fitting::lm_detail::confirm(
        ps, los, his, fixed, equations, at, lambda,
        {lo.function_tolerance, lo.parameter_tolerance, lo.gradient_tolerance, lo.max_iterations}, cost);
  }
  auto residuals_at = [&](const std::vector<double>& q) {
    model(sched, modes, q.data(), m, rel);
    residuals.resize(n);
    for (std::size_t i = 0; i < n; ++i) residuals[i] = y[i] - m[i];
  };
  if (!c.converged()) {
    fitting::FitResult f = ceres_from(sched, modes, y, prob, lo, p);
    for (std::size_t j = 0; j < k; ++j) p[j] = f.params[j].value;
    residuals_at(p);
    variance_factor = fitting::residual_variance_factor(residuals);
    return f;
  }
  residuals = memo.take(std::span<const double>(p));
  if (residuals.size() != n) residuals_at(p);  // not expected: the end point is a kept evaluation
  // The residuals' correlation on another core, beside the diagnostics and the covariance.
  auto factor = std::async(std::launch::async, [&residuals] { return fitting::residual_variance_factor(residuals); });
  fitting::FitResult f = normal_solve_result(y, residuals, prob, p, at.N, c, lo.confidence);
  variance_factor = factor.get();
  return f;
}

}  // namespace

const std::vector<double>& axis_channel(const AccelRecord& r) {
  const std::string want = fmt::format("accel_{}", r.axis);
  for (std::size_t c = 0; c < r.channel_names.size(); ++c)
    if (r.channel_names[c] == want) return r.channels[c];
  throw InputError(fmt::format("the record has no {} column for its axis", want), r.path);
}

AxisResponseInput::AxisResponseInput(std::span<const double> channel, double start_time_s, double sample_rate_hz,
                                     const std::string& path, const std::vector<AccelPiece>& motion)
    : data_(std::make_unique<Data>()) {
  const double dt = 1.0 / sample_rate_hz;
  // The record from the first piece of motion that starts within it: before that the axis rests,
  // and what rings there is the motion before the record, of every mode the sensor feels (another
  // axis' too, through its cross-axis sensitivity), which the model does not follow. Each mode's
  // state where the fit starts is estimated; by the motion's start the ringing has mostly died out.
  const auto first =
      std::find_if(motion.begin(), motion.end(), [&](const AccelPiece& p) { return p.t0_s > start_time_s; });
  const std::size_t skip =
      first == motion.end() || channel.empty()
          ? 0
          : std::min(channel.size() - 1, static_cast<std::size_t>(std::floor((first->t0_s - start_time_s) / dt)));
  data_->y.assign(channel.begin() + static_cast<std::ptrdiff_t>(skip), channel.end());
  const std::size_t n = data_->y.size();
  const double t_first = start_time_s + static_cast<double>(skip) * dt;
  if (n < 16) throw InputError("the record ends where the commanded motion starts", path);
  data_->sched = make_schedule(motion, t_first, dt, n);
  if (data_->sched.pieces_used == 0)
    throw InputError(fmt::format("the commanded motion does not overlap the record ({:.6g} s to {:.6g} s)", t_first,
                                 t_first + static_cast<double>(n - 1) * dt),
                     path);
}

AxisResponseInput::AxisResponseInput(const AccelRecord& record, const std::vector<AccelPiece>& motion)
    : AxisResponseInput(axis_channel(record), record.start_time_s, record.sampling.sample_rate_hz, record.path,
                        motion) {}

std::future<AxisResponseInput> prepare_axis_response(const AccelRecord& record,
                                                     std::function<std::vector<AccelPiece>()> read_motion) {
  std::span<const double> channel;
  std::exception_ptr no_channel;
  try {
    channel = axis_channel(record);
  } catch (const InputError&) {
    no_channel = std::current_exception();
  }
  return std::async(std::launch::async,
                    [channel, no_channel, start = record.start_time_s, rate = record.sampling.sample_rate_hz,
                     path = record.path, read_motion = std::move(read_motion)] {
                      const std::vector<AccelPiece> motion = read_motion();
                      if (no_channel) std::rethrow_exception(no_channel);
                      return AxisResponseInput(channel, start, rate, path, motion);
                    });
}

AxisResponseInput::AxisResponseInput(AxisResponseInput&&) noexcept = default;
AxisResponseInput& AxisResponseInput::operator=(AxisResponseInput&&) noexcept = default;
AxisResponseInput::~AxisResponseInput() = default;

AxisResponseFit fit_axis_response(const AxisResponseInput& input, const std::vector<fitting::ModeStart>& starts,
                                  const AxisResponseOptions& o) {
  if (starts.empty()) throw InputError("output-error fit: no modes to start from");
  const std::vector<double>& y = input.data().y;
  const Schedule& sched = input.data().sched;
  const std::size_t n = y.size(), modes = starts.size();
  fitting::LsqProblem prob;
  prob.params = params_for(starts, o.max_zeta);
  prob.num_residuals = static_cast<int>(n);
  fitting::LsqOptions lo;
  lo.max_iterations = 100;
  lo.function_tolerance = 1e-12;
  lo.parameter_tolerance = 1e-12;
  lo.gradient_tolerance = 1e-14;
  lo.confidence = o.confidence;
  AxisResponseFit out;
  std::vector<double> res;
  out.fit = solve_record(sched, modes, y, prob, lo, res, out.variance_inflation);
  out.samples = n;
  out.pieces = sched.pieces_used;
  finish(out, modes, o.confidence);
  return out;
}

AxisResponseFit fit_axis_response(const AccelRecord& record, const std::vector<AccelPiece>& motion,
                                  const std::vector<fitting::ModeStart>& starts, const AxisResponseOptions& o) {
  if (starts.empty()) throw InputError("output-error fit: no modes to start from");
  return fit_axis_response(AxisResponseInput(record, motion), starts, o);
}

namespace {

/// Why the fit against the motion is not believed beside the spectrum's (empty: it is).
std::string disagreement(const std::vector<fitting::ModeEstimate>& spectrum,
                         const std::vector<fitting::ModeEstimate>& motion) {
  for (std::size_t k = 0; k < spectrum.size() && k < motion.size(); ++k) {
    const auto& s = spectrum[k];
    const auto& t = motion[k];
    const double f_hw = 0.5 * (s.freq_ci95_hi - s.freq_ci95_lo), z_hw = 0.5 * (s.zeta_ci95_hi - s.zeta_ci95_lo);
    if (std::abs(t.freq_hz - s.freq_hz) > kMotionFitAgreementHalfWidths * f_hw ||
        std::abs(t.zeta - s.zeta) > kMotionFitAgreementHalfWidths * z_hw)
      return fmt::format(
          "against the commanded motion f {:.4g} Hz, zeta {:.4g}; the spectrum's f {:.4g} Hz "
          "[{:.4g}, {:.4g}], zeta {:.4g} [{:.4g}, {:.4g}]",
          t.freq_hz, t.zeta, s.freq_hz, s.freq_ci95_lo, s.freq_ci95_hi, s.zeta, s.zeta_ci95_lo, s.zeta_ci95_hi);
  }
  return {};
}

}  // namespace

namespace {

/// refine_modes_with_motion with the input prepared by `prepare` (whose errors become the warning).
template <class Prepare>
void refine_with(AxisModes& m, Prepare&& prepare) {
  if (m.modes.empty()) return;
  std::vector<fitting::ModeStart> starts;
  for (const auto& e : m.modes) starts.push_back({e.freq_hz, e.zeta, 1.0});
  try {
    auto fit = fit_axis_response(prepare(), starts);
    if (const auto why = disagreement(m.modes, fit.modes); !why.empty()) {
      m.warnings.push_back("the fit against the commanded motion does not agree with the spectrum's (" + why +
                           "); the modes are the spectrum's. Is the motion on the samples' clock?");
      return;
    }
    const double strongest = m.peaks.front().freq_hz;
    m.modes = fit.modes;
    m.method = "output_error";
    m.time_fit_variance_inflation = fit.variance_inflation;
    m.time_fit = std::move(fit.fit);
    double best = 1e300;
    for (std::size_t k = 0; k < m.modes.size(); ++k)
      if (std::abs(m.modes[k].freq_hz - strongest) < best) {
        best = std::abs(m.modes[k].freq_hz - strongest);
        m.dominant = static_cast<int>(k);
      }
  } catch (const Error& e) {
    m.warnings.push_back("the fit against the commanded motion failed (" + e.message() +
                         "); the modes are the spectrum's");
  }
}

}  // namespace

void refine_modes_with_motion(AxisModes& m, const AccelRecord& record, const std::vector<AccelPiece>& motion) {
  refine_with(m, [&] { return AxisResponseInput(record, motion); });
}

void refine_modes_with_motion(AxisModes& m, std::future<AxisResponseInput>& input) {
  refine_with(m, [&] { return input.get(); });
}

}  // namespace tunekit::ident
