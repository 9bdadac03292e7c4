// The store's simulation with its forward sensitivities (liquefier_model_sim.hpp).
//
// One step over a time h with the input going linearly from u0 to u0 + du, the store linearised
// at V (q = q(V), tau = dV/dq = a q^b, z = h / tau):
//   V' = V + (u0 - q) tau e1 + du tau (1 - e1 / z),   e1 = 1 - exp(-z),
// the exact solution of the linearised store (exact for b = 0). Its derivatives follow by the
// chain rule through q(V, ln a, b) and tau(V, ln a, b) (dq/dV = 1 / tau, dtau/dV = b / q) and
// through h, u0 and du, which depend on theta where a piece starts or ends at a delayed
// breakpoint or interpolates the input.
#include "liquefier_model_sim.hpp"

#include <cmath>

namespace tunekit::fitting::liquefier_detail {
namespace {

/// e1 / z^2 - E / z (e1 = 1 - exp(-z), E = exp(-z)), by its series where the two terms cancel.
double small_z_bracket(double z, double e1, double E) {
  if (z < 1e-3) return 0.5 - z / 3.0 + z * z / 8.0;
  return e1 / (z * z) - E / z;
}

/// c[0] + c[1] x + ... + c[7] x^7 by Estrin's scheme (a short chain of dependent operations).
inline double poly7(const double* c, double x) {
  const double x2 = x * x, x4 = x2 * x2;
  const double p01 = c[0] + c[1] * x, p23 = c[2] + c[3] * x, p45 = c[4] + c[5] * x, p67 = c[6] + c[7] * x;
  return (p01 + p23 * x2) + (p45 + p67 * x2) * x4;
}

// (1 - exp(-z)) / z and (1 - (1 - exp(-z)) / z) / z for 0 <= z <= 0.02 by their series (the
// terms left off are below 1e-19 of them).
constexpr double kE1z[8] = {1.0, -1.0 / 2, 1.0 / 6, -1.0 / 24, 1.0 / 120, -1.0 / 720, 1.0 / 5040, -1.0 / 40320};
constexpr double kGz[8] = {1.0 / 2, -1.0 / 6, 1.0 / 24, -1.0 / 120, 1.0 / 720, -1.0 / 5040, 1.0 / 40320, -1.0 / 362880};
constexpr double kSeriesZ = 0.02;
// log1p(x) / x for |x| <= 0.01 (the terms left off are below 1e-17 of it).
constexpr double kLog1p[8] = {1.0, -1.0 / 2, 1.0 / 3, -1.0 / 4, 1.0 / 5, -1.0 / 6, 1.0 / 7, -1.0 / 8};

/// The store's state, its sensitivities S = dV/d(ln a, b, theta, V0), and q(V) and 1 / V kept.
class Store {
 public:
  Store(const SimParams& p, bool sens) : A_(p.ln_a), b_(p.b), sens_(sens), sens_b_(sens && p.b_free) {
    bp1_ = b_ + 1.0;
    inv_bp1_ = 1.0 / bp1_;
    ln_bp1_ = std::log(bp1_);
    a_ = std::exp(A_);
    inv_a_ = 1.0 / a_;
    // (1 + x)^(1/(b+1)) - 1 = x sum_n k[n] x^n, the binomial series (k[n] = C(1/(b+1), n+1)).
    double k = inv_bp1_;
    for (int n = 0; n < 8; ++n) {
      binom_[n] = k;
      k *= (inv_bp1_ - (n + 1)) / (n + 2);
    }
    binom_x_max_ = 0.01 / std::max(1.0, inv_bp1_);
    set(p.v0 > 0 ? p.v0 : 0.0);
    if (V_ > 0) S_[3] = 1.0;
  }

  /// A step of length h (dh: dh/dtheta) with the input from u0 (du0: du0/dtheta) rising by du (ddu).
  void step(double h, double dh, double u0, double du0, double du, double ddu) {
    if (!(h > 0)) {
      // A piece of zero length whose end moves with theta (a delayed breakpoint on an output
      // instant): the limit of the step for h -> 0, which the pieces beside it take up.
      if (sens_ && dh != 0.0 && V_ > 0) S_[2] += (u0 - q_ + 0.5 * du) * dh;
      return;
    }
    if (!(V_ > 0)) {
      empty_step(h, dh, u0, du0, du, ddu);
      return;
    }
    // z = h / tau with tau = (b+1) V / q; T1 = tau e1 = h e1/z, T2 = tau g = h g/z.
    const double z = h * inv_bp1_ * q_ * r_;
    double e1z, gz;
    if (z <= kSeriesZ) {  // the short steps of a fast record: no library call
      e1z = poly7(kE1z, z);
      gz = poly7(kGz, z);
    } else {
      e1z = e1_of(z) / z;
      gz = (1.0 - e1z) / z;
    }
    const double T1 = h * e1z, T2 = h * gz;
    const double D = u0 - q_;
    const double Vn = V_ + D * T1 + du * T2;
    if (!(Vn > 0)) {
      zero();
      return;
    }
    if (sens_) {
      const double e1 = z * e1z, g = z * gz, E = 1.0 - e1;
      const double tau = h / z, inv_q = 1.0 / q_;
      const double Ptau = D * (e1 - z * E) + du * (2.0 * g - e1);
      const double Ph = D * E + du * small_z_bracket(z, e1, E);
      const double PV = E + Ptau * b_ * inv_q;
      const double PA = (T1 * q_ + Ptau * tau) * inv_bp1_;
      const double c = (1.0 - bp1_ * L_) * inv_bp1_ * inv_bp1_;
      const double Pb = -T1 * q_ * c + Ptau * (V_ * inv_q - tau * c);
      S_[0] = PV * S_[0] + PA;
      S_[1] = sens_b_ ? PV * S_[1] + Pb : 0.0;
      S_[2] = PV * S_[2] + Ph * dh + T1 * du0 + T2 * ddu;
      S_[3] = PV * S_[3];
    }
    advance(Vn);
  }

  double volume() const { return V_; }
  double flow() const { return q_; }
  /// dV/d(ln a, b, theta, V0).
  void volume_sens(double* row) const {
    for (int i = 0; i < 4; ++i) row[i] = S_[i];
  }
  /// dq/d(ln a, b, theta, V0).
  void flow_sens(double* row) const {
    if (!(V_ > 0)) {
      for (int i = 0; i < 4; ++i) row[i] = 0.0;
      return;
    }
    const double inv_tau = q_ * r_ * inv_bp1_;
    const double c = (1.0 - bp1_ * L_) * inv_bp1_ * inv_bp1_;
    row[0] = S_[0] * inv_tau - q_ * inv_bp1_;
    row[1] = sens_b_ ? S_[1] * inv_tau + q_ * c : 0.0;
    row[2] = S_[2] * inv_tau;
    row[3] = S_[3] * inv_tau;
  }

 private:
  /// The state V and q, 1 / V (and ln q when the sensitivity to b is wanted) at it.
  void set(double V) {
    V_ = V;
    if (!(V_ > 0)) {
      q_ = 0.0;
      return;
    }
    r_ = 1.0 / V_;
    if (b_ == 0.0) {  // the linear store: q = V / a, no logarithm needed
      q_ = V_ * inv_a_;
      if (sens_b_) L_ = std::log(q_);
      return;
    }
    L_ = (ln_bp1_ + std::log(V_) - A_) * inv_bp1_;
    q_ = std::exp(L_);
  }
  /// The state after a step. q = q_old (V / V_old)^(1/(b+1)) by the binomial series when the
  /// relative change of V is small (and ln q by log1p's); in full when it is larger and every
  /// 1024 steps (so that rounding cannot accumulate).
  void advance(double Vn) {
    if (b_ != 0.0 && since_full_ < 1024) {
      const double x = (Vn - V_) * r_;
      if (std::abs(x) <= binom_x_max_) {
        q_ += q_ * x * poly7(binom_, x);
        if (sens_b_) L_ += x * poly7(kLog1p, x) * inv_bp1_;
        V_ = Vn;
        r_ = 1.0 / Vn;
        ++since_full_;
        return;
      }
    }
    since_full_ = 0;
    set(Vn);
  }
  void zero() {
    V_ = 0.0;
    q_ = 0.0;
    for (double& s : S_) s = 0.0;
  }
  /// 1 - exp(-z); the last value is kept (the linear store sees the same z step after step).
  double e1_of(double z) {
    if (z != last_z_) {
      last_z_ = z;
      last_e1_ = -std::expm1(-z);
    }
    return last_e1_;
  }
  /// The empty store: for b <= 0 it fills without outflow (tau infinite); for b > 0 with the time
  /// constant at the flow it is fed with.
  void empty_step(double h, double dh, double u0, double du0, double du, double ddu) {
    if (bp1_ <= 1.0) {
      const double Vn = (u0 + 0.5 * du) * h;
      if (!(Vn > 0)) {
        zero();
        return;
      }
      S_[0] = S_[1] = S_[3] = 0.0;
      S_[2] = (u0 + 0.5 * du) * dh + (du0 + 0.5 * ddu) * h;
      set(Vn);
      return;
    }
    const double u1 = u0 + du;
    const bool hi1 = u1 > u0;
    const double uq = hi1 ? u1 : u0, duq = hi1 ? du0 + ddu : du0;
    if (!(uq > 0)) {
      zero();
      return;
    }
    const double ln_uq = std::log(uq);
    const double tau = std::exp(A_ + b_ * ln_uq);
    const double z = h / tau;
    const double e1 = -std::expm1(-z);
    const double E = 1.0 - e1;
    const double T1 = tau * e1, T2 = tau * (1.0 - e1 / z);
    const double Vn = u0 * T1 + du * T2;
    if (!(Vn > 0)) {
      zero();
      return;
    }
    const double Ptau = u0 * (e1 - z * E) + du * (1.0 - 2.0 * e1 / z + E);
    const double Ph = u0 * E + du * small_z_bracket(z, e1, E);
    S_[0] = Ptau * tau;
    S_[1] = Ptau * tau * ln_uq;
    S_[2] = Ph * dh + T1 * du0 + T2 * ddu + Ptau * b_ * tau / uq * duq;
    S_[3] = 0.0;
    set(Vn);
  }

  double A_, b_, a_ = 1, inv_a_ = 1, bp1_ = 1, inv_bp1_ = 1, ln_bp1_ = 0;
  double binom_[8] = {}, binom_x_max_ = 0;
  bool sens_, sens_b_;
  double V_ = 0, q_ = 0, r_ = 0, L_ = 0;
  double S_[4] = {0, 0, 0, 0};
  double last_z_ = -1, last_e1_ = 0;
  int since_full_ = 0;
};

}  // namespace

std::vector<std::size_t> input_kinks(const InputTrack& in) {
  std::vector<std::size_t> k;
  for (std::size_t j = 0; j < in.n; ++j) {
    const double left = j > 0 ? in.u[j - 1] : in.u[j];
    const double right = j + 1 < in.n ? in.u[j + 1] : in.u[j];
    if (!(left == in.u[j] && in.u[j] == right)) k.push_back(j);
  }
  return k;
}

void simulate(const double* t, std::size_t n, const InputTrack& in, const SimParams& p, bool volume, int max_substeps,
              double h_max, double* out, double* sens) {
  std::vector<std::size_t> own;
  const std::size_t* K = in.kinks;
  std::size_t nk = in.n_kinks;
  if (K == nullptr) {
    own = input_kinks(in);
    K = own.data();
    nk = own.size();
  }
  Store st(p, sens != nullptr);
  auto emit = [&](std::size_t k) {
    out[k] = volume ? st.volume() : st.flow();
    if (sens != nullptr) volume ? st.volume_sens(sens + 4 * k) : st.flow_sens(sens + 4 * k);
  };
  emit(0);
  const double th = p.theta;
  std::size_t m = 0;  // the first kink whose delayed time lies after the current time
  while (m < nk && in.t[K[m]] + th <= t[0]) ++m;
  // u(s - theta) between the kinks m-1 and m (flat unless they are neighbours), and its
  // derivative with respect to theta (- slope).
  auto delayed = [&](double s, double& d_theta) -> double {
    d_theta = 0.0;
    if (m == 0) return in.u[0];
    if (m >= nk) return in.u[in.n - 1];
    const std::size_t ka = K[m - 1], kb = K[m];
    if (kb != ka + 1) return in.u[ka];
    const double slope = (in.u[kb] - in.u[ka]) / (in.t[kb] - in.t[ka]);
    d_theta = -slope;
    return in.u[ka] + slope * (s - th - in.t[ka]);
  };
  int substeps = max_substeps;
  double inv_sub = 1.0 / substeps;
  // The piece from s to e with the input from us to ue; ds, de, dus, due their theta-derivatives.
  auto piece = [&](double s, double ds, double e, double de, double us, double dus, double ue, double due) {
    const double h = (e - s) * inv_sub, dh = (de - ds) * inv_sub;
    const double du = (ue - us) * inv_sub, ddu = (due - dus) * inv_sub;
    for (int i = 0; i < substeps; ++i) st.step(h, dh, us + du * double(i), dus + ddu * double(i), du, ddu);
  };
  for (std::size_t k = 0; k + 1 < n; ++k) {
    if (h_max > 0) {
      const double c = std::ceil((t[k + 1] - t[k]) / h_max);
      substeps = c >= max_substeps ? max_substeps : (c > 1 ? static_cast<int>(c) : 1);
      inv_sub = 1.0 / substeps;
    }
    double s = t[k], ds = 0.0, dus = 0.0;
    double us = delayed(t[k], dus);
    while (m < nk && in.t[K[m]] + th < t[k + 1]) {
      const double e = in.t[K[m]] + th;
      piece(s, ds, e, 1.0, us, dus, in.u[K[m]], 0.0);
      s = e;
      ds = 1.0;
      us = in.u[K[m]];
      dus = 0.0;
      ++m;
    }
    double due = 0.0;
    const double ue = delayed(t[k + 1], due);
    piece(s, ds, t[k + 1], 0.0, us, dus, ue, due);
    emit(k + 1);
  }
}

}  // namespace tunekit::fitting::liquefier_detail
