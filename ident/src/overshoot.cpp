#include "tunekit/ident/overshoot.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"

namespace tunekit::ident {
namespace {

struct OvershootPauseWindow {
  std::size_t begin = 0, end = 0;  // sample indices, end inclusive
  std::size_t motion_begin = 0;    // first sample of the motion before the pause
  double move[2] = {0, 0};         // commanded displacement per axis (mm)
};

// Least-squares polynomial baseline of the given order over a whole pause: the unknown start
// position and velocity of the double integration (order 1), a constant sensor offset (2) and
// the low-frequency random walk of integrated noise (3). A ringing mode of several periods in
// the pause projects little onto it.
std::vector<double> overshoot_baseline(const std::vector<double>& t, std::size_t begin, const std::vector<double>& y,
                                       int order) {
  const std::size_t n = y.size();
  const int m = order + 1;
  const double t0 = t[begin], span = std::max(t[begin + n - 1] - t0, 1e-12);
  std::vector<double> ata(static_cast<std::size_t>(m * m), 0.0), aty(static_cast<std::size_t>(m), 0.0);
  std::vector<double> pw(static_cast<std::size_t>(m));
  for (std::size_t k = 0; k < n; ++k) {
    const double x = 2 * (t[begin + k] - t0) / span - 1;
    pw[0] = 1;
    for (int j = 1; j < m; ++j) pw[static_cast<std::size_t>(j)] = pw[static_cast<std::size_t>(j - 1)] * x;
    for (int i = 0; i < m; ++i) {
      aty[static_cast<std::size_t>(i)] += pw[static_cast<std::size_t>(i)] * y[k];
      for (int j = 0; j < m; ++j)
        ata[static_cast<std::size_t>(i * m + j)] += pw[static_cast<std::size_t>(i)] * pw[static_cast<std::size_t>(j)];
    }
  }
  // Gaussian elimination with partial pivoting (m <= 6).
  std::vector<double> c = aty;
  for (int col = 0; col < m; ++col) {
    int piv = col;
    for (int r = col + 1; r < m; ++r)
      if (std::abs(ata[static_cast<std::size_t>(r * m + col)]) > std::abs(ata[static_cast<std::size_t>(piv * m + col)]))
        piv = r;
    if (piv != col) {
      for (int j = 0; j < m; ++j)
        std::swap(ata[static_cast<std::size_t>(col * m + j)], ata[static_cast<std::size_t>(piv * m + j)]);
      std::swap(c[static_cast<std::size_t>(col)], c[static_cast<std::size_t>(piv)]);
    }
    const double d = ata[static_cast<std::size_t>(col * m + col)];
    if (std::abs(d) < 1e-300) continue;
    for (int r = col + 1; r < m; ++r) {
      const double f = ata[static_cast<std::size_t>(r * m + col)] / d;
      for (int j = col; j < m; ++j)
        ata[static_cast<std::size_t>(r * m + j)] -= f * ata[static_cast<std::size_t>(col * m + j)];
      c[static_cast<std::size_t>(r)] -= f * c[static_cast<std::size_t>(col)];
    }
  }
  for (int r = m - 1; r >= 0; --r) {
    double s = c[static_cast<std::size_t>(r)];
    for (int j = r + 1; j < m; ++j) s -= ata[static_cast<std::size_t>(r * m + j)] * c[static_cast<std::size_t>(j)];
    const double d = ata[static_cast<std::size_t>(r * m + r)];
    c[static_cast<std::size_t>(r)] = std::abs(d) < 1e-300 ? 0.0 : s / d;
  }
  std::vector<double> out(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double x = 2 * (t[begin + k] - t0) / span - 1;
    double v = 0, p = 1;
    for (int j = 0; j < m; ++j) {
      v += c[static_cast<std::size_t>(j)] * p;
      p *= x;
    }
    out[k] = v;
  }
  return out;
}

// Settling, residual amplitude and frequency of a deviation trace starting at the motion end.
void overshoot_fill_corner(CornerResult& c, double direction, std::size_t tail_begin, const OvershootOptions& o) {
  const auto& z = c.deviation_mm;
  const auto& t = c.t_s;
  double peak = 0, amp = 0;
  std::size_t last_out = z.size();
  for (std::size_t i = 0; i < z.size(); ++i) {
    peak = std::max(peak, direction * z[i]);
    amp = std::max(amp, std::abs(z[i]));
    if (std::abs(z[i]) > o.band_mm) last_out = i;
  }
  c.overshoot_mm = peak;
  c.overshoot_pct = std::abs(c.move_mm) > 0 ? 100.0 * peak / std::abs(c.move_mm) : 0.0;
  c.residual_amplitude_mm = amp;
  if (last_out == z.size()) c.settling_time_s = 0;
  else c.settling_time_s = (last_out + 1 < z.size() ? t[last_out + 1] : t.back()) - c.t_motion_end_s;
  c.settled = last_out == z.size() || last_out < tail_begin;
  // Zero crossings with hysteresis: a crossing counts once the trace has gone past -h / +h.
  const double h = std::max(0.5 * o.band_mm, 0.05 * amp);
  int sign = 0;
  double last_zero = t.empty() ? 0 : t.front();
  std::vector<double> crossings;
  for (std::size_t i = 0; i < z.size(); ++i) {
    if (i > 0 && (z[i - 1] < 0) != (z[i] < 0)) {
      const double f = z[i - 1] / (z[i - 1] - z[i]);
      last_zero = t[i - 1] + f * (t[i] - t[i - 1]);
    }
    if (std::abs(z[i]) > h) {
      const int s = z[i] > 0 ? 1 : -1;
      if (sign != 0 && s != sign) crossings.push_back(last_zero);
      sign = s;
    }
  }
  c.residual_freq_hz = crossings.size() >= 2
                           ? static_cast<double>(crossings.size() - 1) / (2 * (crossings.back() - crossings.front()))
                           : 0.0;
}

void overshoot_summarize(OvershootAnalysis& a) {
  for (const char* axis : {"x", "y"}) {
    AxisOvershootSummary s;
    s.axis = axis;
    std::vector<double> freqs;
    for (const auto& c : a.corners) {
      if (c.axis != axis) continue;
      ++s.corners;
      s.mean_overshoot_mm += c.overshoot_mm;
      s.mean_overshoot_pct += c.overshoot_pct;
      s.max_overshoot_mm = std::max(s.max_overshoot_mm, c.overshoot_mm);
      s.mean_settling_time_s += c.settling_time_s;
      s.max_settling_time_s = std::max(s.max_settling_time_s, c.settling_time_s);
      s.mean_residual_amplitude_mm += c.residual_amplitude_mm;
      if (c.residual_freq_hz > 0) freqs.push_back(c.residual_freq_hz);
    }
    if (s.corners == 0) continue;
    const double n = s.corners;
    s.mean_overshoot_mm /= n;
    s.mean_overshoot_pct /= n;
    s.mean_settling_time_s /= n;
    s.mean_residual_amplitude_mm /= n;
    if (!freqs.empty()) {
      std::sort(freqs.begin(), freqs.end());
      const std::size_t m = freqs.size() / 2;
      s.median_residual_freq_hz = freqs.size() % 2 ? freqs[m] : 0.5 * (freqs[m - 1] + freqs[m]);
    }
    a.axes.push_back(s);
  }
}

void overshoot_check_series(const std::vector<double>& t, const std::vector<const std::vector<double>*>& cols) {
  if (t.size() < 16) throw InputError(fmt::format("too few samples ({}) for an overshoot analysis", t.size()));
  for (std::size_t i = 1; i < t.size(); ++i)
    if (!(t[i] > t[i - 1])) throw InputError(fmt::format("time is not increasing at sample {}", i + 1));
  for (const auto* c : cols)
    if (!c->empty() && c->size() != t.size()) throw InputError("overshoot: columns of different lengths");
}

// The pauses after commanded motion: the commanded velocity and displacement by integration of
// the commanded accelerations, reset at every pause; a rest counts as a pause when the velocity
// has fallen below max(2 mm/s, 10 % of the motion's peak) and it lasts min_pause_s.
std::vector<OvershootPauseWindow> commanded_pauses(const std::vector<double>& t,
                                                   const std::vector<double>* const cmd[2], const OvershootOptions& o) {
  const std::size_t n = t.size();
  auto active = [&](std::size_t i) {
    return std::abs((*cmd[0])[i]) > o.accel_zero_mm_s2 || std::abs((*cmd[1])[i]) > o.accel_zero_mm_s2;
  };
  std::vector<OvershootPauseWindow> pauses;
  double v[2] = {0, 0}, d[2] = {0, 0}, vpeak = 0;
  bool in_motion = false;
  std::size_t motion_begin = 0;
  std::size_t i = 0;
  // A record that starts inside a motion (e.g. the shaped tail of the move before recording
  // began) has no known start velocity: skip to its first rest.
  while (i < n && active(i)) ++i;
  while (i < n) {
    if (active(i)) {
      if (!in_motion) {
        in_motion = true;
        motion_begin = i;
        v[0] = v[1] = d[0] = d[1] = vpeak = 0;
      }
      const std::size_t b = i;
      while (i < n && active(i)) ++i;
      for (std::size_t k = std::max<std::size_t>(b, 1); k < std::min(i + 1, n); ++k) {
        const double dt = t[k] - t[k - 1];
        for (int a = 0; a < 2; ++a) {
          const double v0 = v[a];
          v[a] += 0.5 * ((*cmd[a])[k - 1] + (*cmd[a])[k]) * dt;
          d[a] += 0.5 * (v0 + v[a]) * dt;
        }
        vpeak = std::max({vpeak, std::abs(v[0]), std::abs(v[1])});
      }
      continue;
    }
    const std::size_t b = i;
    while (i < n && !active(i)) ++i;
    const std::size_t e = i - 1;
    if (!in_motion) continue;
    const double vthr = std::max(2.0, 0.1 * vpeak);
    if (std::abs(v[0]) < vthr && std::abs(v[1]) < vthr) {
      if (t[e] - t[b] >= o.min_pause_s) pauses.push_back({b, e, motion_begin, {d[0], d[1]}});
      in_motion = false;
    } else {
      // Cruise: constant commanded velocity until the next active run.
      const double dt = (e + 1 < n ? t[e + 1] : t[e]) - t[b];
      d[0] += v[0] * dt;
      d[1] += v[1] * dt;
    }
  }
  return pauses;
}

// The corner of axis a over pause p: the residual acceleration (measured - commanded) over the
// pause, integrated twice from an unknown start, less its drift.
CornerResult residual_corner(const std::vector<double>& t, const OvershootPauseWindow& p, int a,
                             const std::vector<double>& meas, const std::vector<double>& cmd, int corner,
                             const OvershootOptions& o) {
  const std::size_t len = p.end - p.begin + 1;
  const std::size_t tail =
      p.begin + static_cast<std::size_t>(std::floor((1 - o.tail_fraction) * static_cast<double>(len)));
  std::vector<double> pos(len, 0.0);
  double vel = 0;
  for (std::size_t k = 1; k < len; ++k) {
    const double dt = t[p.begin + k] - t[p.begin + k - 1];
    const double r0 = meas[p.begin + k - 1] - cmd[p.begin + k - 1];
    const double r1 = meas[p.begin + k] - cmd[p.begin + k];
    const double v0 = vel;
    vel += 0.5 * (r0 + r1) * dt;
    pos[k] = pos[k - 1] + 0.5 * (v0 + vel) * dt;
  }
  const std::vector<double> drift = overshoot_baseline(t, p.begin, pos, o.drift_order);
  CornerResult c;
  c.index = corner;
  c.axis = a == 0 ? "x" : "y";
  c.t_motion_start_s = t[p.motion_begin];
  c.t_motion_end_s = t[p.begin];
  c.move_mm = p.move[a];
  c.t_s.resize(len);
  c.deviation_mm.resize(len);
  for (std::size_t k = 0; k < len; ++k) {
    c.t_s[k] = t[p.begin + k];
    c.deviation_mm[k] = pos[k] - drift[k];
  }
  overshoot_fill_corner(c, p.move[a] > 0 ? 1.0 : -1.0, tail - p.begin, o);
  return c;
}

}  // namespace

OvershootAnalysis analyze_overshoot_accel(const std::vector<double>& t, const std::vector<double>& ax,
                                          const std::vector<double>& ay, const std::vector<double>& cmd_ax,
                                          const std::vector<double>& cmd_ay, const OvershootOptions& o) {
  overshoot_check_series(t, {&ax, &ay, &cmd_ax, &cmd_ay});
  if (ax.size() != t.size() || ay.size() != t.size() || cmd_ax.size() != t.size() || cmd_ay.size() != t.size())
    throw InputError("overshoot from an accelerometer needs accel_x, accel_y and the commanded accel_x, accel_y");
  const std::vector<double>* cmd[2] = {&cmd_ax, &cmd_ay};
  const std::vector<double>* meas[2] = {&ax, &ay};
  const std::vector<OvershootPauseWindow> pauses = commanded_pauses(t, cmd, o);
  OvershootAnalysis res;
  res.source = "accelerometer";
  int corner = 0;
  for (const auto& p : pauses) {
    bool any = false;
    for (int a = 0; a < 2; ++a) {
      if (std::abs(p.move[a]) < o.min_move_mm) continue;
      any = true;
      res.corners.push_back(residual_corner(t, p, a, *meas[a], *cmd[a], corner, o));
    }
    if (any) {
      res.motion_time_s += t[p.begin] - t[p.motion_begin];
      ++corner;
    }
  }
  if (res.corners.empty())
    throw InputError("no corner found: no commanded motion followed by a pause of at least " +
                     fmt::format("{:g} s", o.min_pause_s));
  overshoot_summarize(res);
  return res;
}

OvershootAnalysis analyze_overshoot_position(const std::vector<double>& t, const std::vector<double>& x,
                                             const std::vector<double>& y, const OvershootOptions& o) {
  overshoot_check_series(t, {&x, &y});
  if (x.empty() && y.empty()) throw InputError("overshoot from positions needs an x or a y position column");
  const std::size_t n = t.size();
  const std::vector<double>* col[2] = {&x, &y};
  // Speed smoothed over ~20 ms: rests are where it stays below 5 mm/s.
  std::vector<bool> still(n, true);
  for (std::size_t i = 0; i < n; ++i) {
    std::size_t lo = i, hi = i;
    while (lo > 0 && t[i] - t[lo - 1] <= 0.01) --lo;
    while (hi + 1 < n && t[hi + 1] - t[i] <= 0.01) ++hi;
    if (hi == lo) continue;
    for (const auto* c : col)
      if (!c->empty() && std::abs(((*c)[hi] - (*c)[lo]) / (t[hi] - t[lo])) > 5.0) still[i] = false;
  }
  struct Rest {
    std::size_t b, e;
    double settled[2];
  };
  std::vector<Rest> rests;
  for (std::size_t i = 0; i < n;) {
    if (!still[i]) {
      ++i;
      continue;
    }
    const std::size_t b = i;
    while (i < n && still[i]) ++i;
    if (t[i - 1] - t[b] < o.min_pause_s) continue;
    Rest r{b, i - 1, {0, 0}};
    const std::size_t len = r.e - r.b + 1;
    const std::size_t tail =
        r.b + static_cast<std::size_t>(std::floor((1 - o.tail_fraction) * static_cast<double>(len)));
    for (int a = 0; a < 2; ++a)
      if (!col[a]->empty())
        r.settled[a] = std::accumulate(col[a]->begin() + static_cast<long>(tail),
                                       col[a]->begin() + static_cast<long>(r.e + 1), 0.0) /
                       static_cast<double>(r.e + 1 - tail);
    rests.push_back(r);
  }
  OvershootAnalysis res;
  res.source = "position";
  int corner = 0;
  for (std::size_t k = 1; k < rests.size(); ++k) {
    const auto& prev = rests[k - 1];
    const auto& r = rests[k];
    const std::size_t m0 = prev.e + 1;
    const std::size_t len = r.e - r.b + 1;
    const std::size_t tail =
        r.b + static_cast<std::size_t>(std::floor((1 - o.tail_fraction) * static_cast<double>(len)));
    bool any = false;
    double end_time = t[r.b];
    for (int a = 0; a < 2; ++a) {
      if (col[a]->empty()) continue;
      const double move = r.settled[a] - prev.settled[a];
      if (std::abs(move) < o.min_move_mm) continue;
      any = true;
      const double dir = move > 0 ? 1.0 : -1.0;
      const auto& p = *col[a];
      // The motion ends where the axis first reaches its settled position.
      std::size_t me = r.b;
      for (std::size_t i = m0; i <= r.e; ++i)
        if (dir * (p[i] - r.settled[a]) >= 0 || std::abs(p[i] - r.settled[a]) < o.band_mm) {
          me = std::min(i, r.b);
          break;
        }
      CornerResult c;
      c.index = corner;
      c.axis = a == 0 ? "x" : "y";
      c.t_motion_start_s = t[m0 > 0 ? m0 - 1 : 0];
      c.t_motion_end_s = t[me];
      c.move_mm = move;
      for (std::size_t i = me; i <= r.e; ++i) {
        c.t_s.push_back(t[i]);
        c.deviation_mm.push_back(p[i] - r.settled[a]);
      }
      end_time = std::max(end_time, t[me]);
      overshoot_fill_corner(c, dir, tail - me, o);
      res.corners.push_back(std::move(c));
    }
    if (any) {
      res.motion_time_s += end_time - t[m0 > 0 ? m0 - 1 : 0];
      ++corner;
    }
  }
  if (res.corners.empty())
    throw InputError(fmt::format("no corner found: no move of at least {:g} mm between two rests of at least {:g} s",
                                 o.min_move_mm, o.min_pause_s));
  overshoot_summarize(res);
  return res;
}

nlohmann::json to_json(const OvershootAnalysis& a, bool with_traces) {
  nlohmann::json j;
  j["source"] = a.source;
  j["motion_time_s"] = a.motion_time_s;
  nlohmann::json corners = nlohmann::json::array();
  for (const auto& c : a.corners) {
    nlohmann::json cj{{"index", c.index},
                      {"axis", c.axis},
                      {"t_motion_start_s", c.t_motion_start_s},
                      {"t_motion_end_s", c.t_motion_end_s},
                      {"move_mm", c.move_mm},
                      {"overshoot_mm", c.overshoot_mm},
                      {"overshoot_pct", c.overshoot_pct},
                      {"settling_time_s", c.settling_time_s},
                      {"settled", c.settled},
                      {"residual_amplitude_mm", c.residual_amplitude_mm},
                      {"residual_freq_hz", c.residual_freq_hz}};
    if (with_traces) {
      cj["t_s"] = c.t_s;
      cj["deviation_mm"] = c.deviation_mm;
    }
    corners.push_back(cj);
  }
  j["corners"] = corners;
  nlohmann::json axes = nlohmann::json::object();
  for (const auto& s : a.axes)
    axes[s.axis] = {{"corners", s.corners},
                    {"mean_overshoot_mm", s.mean_overshoot_mm},
                    {"max_overshoot_mm", s.max_overshoot_mm},
                    {"mean_overshoot_pct", s.mean_overshoot_pct},
                    {"mean_settling_time_s", s.mean_settling_time_s},
                    {"max_settling_time_s", s.max_settling_time_s},
                    {"mean_residual_amplitude_mm", s.mean_residual_amplitude_mm},
                    {"median_residual_freq_hz", s.median_residual_freq_hz}};
  j["axes"] = axes;
  return j;
}

double overshoot_figure_of_merit(double overshoot_mm, double tolerance_mm, double completion_s,
                                 double mean_completion_s) {
  if (!(completion_s > 0) || !(mean_completion_s > 0)) return 0;
  return overshoot_mm <= tolerance_mm ? mean_completion_s / completion_s : 0.0;
}

}  // namespace tunekit::ident
