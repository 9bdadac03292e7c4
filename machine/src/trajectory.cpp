#include "tunekit/machine/trajectory.hpp"

#include <algorithm>
#include <cmath>

namespace tunekit::machine {
namespace {

PathState advance(const PathState& s, double jerk, double t) {
  PathState o;
  o.accel_mm_s2 = s.accel_mm_s2 + jerk * t;
  o.vel_mm_s = s.vel_mm_s + s.accel_mm_s2 * t + jerk * t * t / 2;
  o.pos_mm = s.pos_mm + s.vel_mm_s * t + s.accel_mm_s2 * t * t / 2 + jerk * t * t * t / 6;
  return o;
}

}  // namespace

double Profile::ramp_duration(double v0, double v1, double a_max, double j_max) {
  const double dv = std::abs(v1 - v0);
  if (dv <= 0) return 0;
  const double tj = a_max / j_max;
  if (dv >= a_max * tj) return 2 * tj + (dv / a_max - tj);
  return 2 * std::sqrt(dv / j_max);
}

double Profile::ramp_distance(double v0, double v1, double a_max, double j_max) {
  return 0.5 * (v0 + v1) * ramp_duration(v0, v1, a_max, j_max);
}

void Profile::add(double duration, double jerk) {
  if (duration <= 0) return;
  segs_.push_back({duration_, duration, jerk, end_});
  end_ = advance(end_, jerk, duration);
  duration_ += duration;
}

void Profile::add_ramp(double v0, double v1, double a_max, double j_max) {
  const double dv = std::abs(v1 - v0);
  if (dv <= 0) return;
  const double sj = v1 > v0 ? j_max : -j_max;
  const double tj = a_max / j_max;
  if (dv >= a_max * tj) {
    add(tj, sj);
    add(dv / a_max - tj, 0);
    add(tj, -sj);
  } else {
    const double t = std::sqrt(dv / j_max);
    add(t, sj);
    add(t, -sj);
  }
  end_.accel_mm_s2 = 0;  // exact by construction; remove rounding
  end_.vel_mm_s = v1;
}

namespace {

/// A move's speeds: entry, the peak (cruise) speed and the exit speed, after the limits.
struct MoveSpeeds {
  double d = 0, v_entry = 0, vc = 0, v_exit = 0;
};

MoveSpeeds move_speeds(double d, double v_entry, double v_max, double v_exit, double a_max, double j_max) {
  d = std::max(0.0, d);
  v_max = std::max(v_max, 1e-9);
  v_entry = std::max(0.0, v_entry);
  v_exit = std::min(std::max(0.0, v_exit), v_max);
  auto need = [&](double vc) {
    return Profile::ramp_distance(v_entry, vc, a_max, j_max) + Profile::ramp_distance(vc, v_exit, a_max, j_max);
  };
  double vc = v_max;
  if (v_entry == 0 && v_exit == 0 && need(vc) > d && a_max > 0 && j_max > 0) {
    // From rest to rest, too short to reach v_max: the peak speed in closed form (the search
    // below finds the same root; the gate and the planners time many such short moves).
    // need(vc) = vc * ramp_duration(0, vc): vc^2 / a + vc a / j when the ramp reaches a_max,
    // else 2 vc^1.5 / sqrt(j).
    const double tj = a_max / j_max;
    const double full = 0.5 * a_max * (std::sqrt(tj * tj + 4 * d / a_max) - tj);
    vc = full >= a_max * tj ? full : std::cbrt(0.25 * d * d * j_max);
    vc = std::clamp(vc, 0.0, v_max);
  } else if (v_entry <= v_max && need(vc) > d) {
    // Too short to reach v_max: search the peak speed (entering faster than this move's speed,
    // the move slows down to it first, with no search).
    double lo = std::max(v_entry, v_exit), hi = v_max;
    if (need(lo) > d && v_entry > v_exit) {
      // Too short to slow from the entry speed to the exit speed: it leaves faster (a planner's
      // backward pass would have let it enter slower; the distance of the slowing down falls as
      // the exit speed rises).
      double elo = v_exit, ehi = v_entry;
      for (int i = 0; i < 60; ++i) {
        const double m = 0.5 * (elo + ehi);
        v_exit = m;
        (need(v_entry) > d ? elo : ehi) = m;
      }
      v_exit = ehi;
      lo = hi = v_entry;
    } else if (need(lo) > d) {
      // Too short even to go from the entry speed to the exit speed: lower the exit speed (not
      // below the entry speed: the distance grows again under it).
      double elo = v_entry, ehi = v_exit;
      for (int i = 0; i < 60; ++i) {
        const double m = 0.5 * (elo + ehi);
        v_exit = m;
        (need(std::max(v_entry, m)) > d ? ehi : elo) = m;
      }
      v_exit = elo;
      lo = std::max(v_entry, v_exit);
      hi = lo;
    }
    for (int i = 0; i < 60 && hi > lo; ++i) {
      const double m = 0.5 * (lo + hi);
      (need(m) > d ? hi : lo) = m;
    }
    vc = lo;
  }
  return {d, v_entry, vc, v_exit};
}

}  // namespace

Profile Profile::move(double d, double v_entry, double v_max, double v_exit, double a_max, double j_max) {
  const MoveSpeeds m = move_speeds(d, v_entry, v_max, v_exit, a_max, j_max);
  Profile p;
  p.end_.vel_mm_s = m.v_entry;
  p.add_ramp(m.v_entry, m.vc, a_max, j_max);
  const double cruise =
      m.d - ramp_distance(m.v_entry, m.vc, a_max, j_max) - ramp_distance(m.vc, m.v_exit, a_max, j_max);
  if (cruise > 0 && m.vc > 0) p.add(cruise / m.vc, 0);
  p.add_ramp(m.vc, m.v_exit, a_max, j_max);
  return p;
}

double Profile::move_duration_s(double d, double v_entry, double v_max, double v_exit, double a_max, double j_max) {
  const MoveSpeeds m = move_speeds(d, v_entry, v_max, v_exit, a_max, j_max);
  const double cruise =
      m.d - ramp_distance(m.v_entry, m.vc, a_max, j_max) - ramp_distance(m.vc, m.v_exit, a_max, j_max);
  return ramp_duration(m.v_entry, m.vc, a_max, j_max) + (cruise > 0 && m.vc > 0 ? cruise / m.vc : 0.0) +
         ramp_duration(m.vc, m.v_exit, a_max, j_max);
}

Profile Profile::cruise(double v, double duration_s) {
  Profile p;
  p.end_.vel_mm_s = v;
  p.add(duration_s, 0);
  return p;
}

double Profile::distance_mm() const { return end_.pos_mm; }
double Profile::exit_speed() const { return end_.vel_mm_s; }

PathState Profile::at(double t) const {
  if (segs_.empty()) return end_;
  if (t <= 0) return segs_.front().s0;
  if (t >= duration_) return end_;
  auto it = std::upper_bound(segs_.begin(), segs_.end(), t, [](double v, const Segment& s) { return v < s.t0; });
  const Segment& s = *(it - 1);
  return advance(s.s0, s.jerk, t - s.t0);
}

std::vector<Profile::Piece> Profile::pieces() const {
  std::vector<Piece> out;
  out.reserve(segs_.size());
  for (const auto& s : segs_) out.push_back({s.t0, s.duration, s.s0.accel_mm_s2, s.jerk});
  return out;
}

double Profile::peak_accel() const {
  double m = 0;
  for (const auto& s : segs_) {
    m = std::max(m, std::abs(s.s0.accel_mm_s2));
    m = std::max(m, std::abs(advance(s.s0, s.jerk, s.duration).accel_mm_s2));
  }
  return m;
}

}  // namespace tunekit::machine
