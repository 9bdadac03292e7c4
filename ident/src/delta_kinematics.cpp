// Linear delta kinematics: see delta_kinematics.hpp.
#include "tunekit/ident/delta_kinematics.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace tunekit::ident {
namespace {

struct DkVec3 {
  double x, y, z;
};
DkVec3 dk_sub(DkVec3 a, DkVec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
DkVec3 dk_add(DkVec3 a, DkVec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
DkVec3 dk_scale(DkVec3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }
double dk_dot(DkVec3 a, DkVec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
DkVec3 dk_cross(DkVec3 a, DkVec3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }

std::array<double, 2> dk_tower(const DeltaGeometry& g, int i) {
  const double a = g.angle_deg[static_cast<std::size_t>(i)] * std::numbers::pi / 180.0;
  return {g.radius_mm * std::cos(a), g.radius_mm * std::sin(a)};
}

double dk_triple(DkVec3 a, DkVec3 b, DkVec3 c) { return dk_dot(a, dk_cross(b, c)); }

// The weights of DeltaHeightSensitivity: with d_t = q - P_t the rows of D, the constraints give
// D dq = b (b_t = d_t . dP_t + L_t dL_t), and the height w . dq = (D^-T w) . b; the weights solve
// sum_t weight_t d_t = w (Cramer's rule).
bool dk_height_sensitivity(const DkVec3 (&joint)[3], DkVec3 q, DkVec3 w, DeltaHeightSensitivity& s) {
  DkVec3 d[3];
  for (std::size_t t = 0; t < 3; ++t) {
    d[t] = dk_sub(q, joint[t]);
    s.joint_offset[t] = {d[t].x, d[t].y, d[t].z};
  }
  const double det = dk_triple(d[0], d[1], d[2]);
  const double scale = std::sqrt(dk_dot(d[0], d[0]) * dk_dot(d[1], d[1]) * dk_dot(d[2], d[2]));
  if (!(std::abs(det) > 1e-12 * scale)) return false;
  s.weight = {dk_triple(w, d[1], d[2]) / det, dk_triple(d[0], w, d[2]) / det, dk_triple(d[0], d[1], w) / det};
  return true;
}

}  // namespace

bool delta_carriages(const DeltaGeometry& g, const DeltaPoint& p, std::array<double, 3>& c) {
  for (int i = 0; i < 3; ++i) {
    const auto t = dk_tower(g, i);
    const double L = g.rod_mm[static_cast<std::size_t>(i)];
    const double h2 = L * L - (p.x - t[0]) * (p.x - t[0]) - (p.y - t[1]) * (p.y - t[1]);
    if (!(h2 > 0)) return false;
    c[static_cast<std::size_t>(i)] = p.z + std::sqrt(h2) + p.x * g.tilt_x + p.y * g.tilt_y;
  }
  return true;
}

bool delta_position(const DeltaGeometry& g, const std::array<double, 3>& c, DeltaPoint& out) {
  return DeltaForward(g).position(c, out);
}

DeltaForward::DeltaForward(const DeltaGeometry& g) : g_(g) {
  for (int i = 0; i < 3; ++i) towers_[static_cast<std::size_t>(i)] = dk_tower(g, i);
}

bool DeltaForward::position(const std::array<double, 3>& c, DeltaPoint& out, DeltaHeightSensitivity* sens) const {
  // Trilateration of three spheres (centre: tower column at the carriage height, radius:
  // rod length), taking the intersection below the carriages. Tilt is applied after.
  const DeltaGeometry& g = g_;
  DkVec3 p[3];
  for (std::size_t i = 0; i < 3; ++i) p[i] = {towers_[i][0], towers_[i][1], c[i]};
  const double r1 = g.rod_mm[0], r2 = g.rod_mm[1], r3 = g.rod_mm[2];
  const DkVec3 s21 = dk_sub(p[1], p[0]), s31 = dk_sub(p[2], p[0]);
  const double d = std::sqrt(dk_dot(s21, s21));
  if (!(d > 0)) return false;
  const DkVec3 ex = dk_scale(s21, 1.0 / d);
  const double i = dk_dot(ex, s31);
  const DkVec3 vey = dk_sub(s31, dk_scale(ex, i));
  const double ny = std::sqrt(dk_dot(vey, vey));
  if (!(ny > 0)) return false;
  const DkVec3 ey = dk_scale(vey, 1.0 / ny);
  const DkVec3 ez = dk_cross(ex, ey);
  const double j = dk_dot(ey, s31);
  const double x = (r1 * r1 - r2 * r2 + d * d) / (2 * d);
  const double y = (r1 * r1 - r3 * r3 + i * i + j * j) / (2 * j) - x * i / j;
  const double z2 = r1 * r1 - x * x - y * y;
  if (!(z2 >= 0)) return false;
  // ez points up for towers ordered counter-clockwise (A 210, B 330, C 90 degrees).
  const double zs = ez.z > 0 ? -std::sqrt(z2) : std::sqrt(z2);
  const DkVec3 q = dk_add(p[0], dk_add(dk_scale(ex, x), dk_add(dk_scale(ey, y), dk_scale(ez, zs))));
  out = {q.x, q.y, q.z - q.x * g.tilt_x - q.y * g.tilt_y};
  if (!(std::isfinite(out.x) && std::isfinite(out.y) && std::isfinite(out.z))) return false;
  return sens == nullptr || dk_height_sensitivity(p, q, {-g.tilt_x, -g.tilt_y, 1.0}, *sens);
}

std::array<double, 3> delta_homed_carriages(const DeltaGeometry& g) {
  std::array<double, 3> c{};
  for (std::size_t i = 0; i < 3; ++i)
    c[i] = g.homed_height_mm + std::sqrt(g.rod_mm[i] * g.rod_mm[i] - g.radius_mm * g.radius_mm) + g.endstop_mm[i];
  return c;
}

bool delta_true_height(const DeltaGeometry& nominal, const DeltaGeometry& actual, const DeltaProbe& cmd,
                       double& true_height_mm) {
  std::array<double, 3> c{};
  if (!delta_carriages(nominal, {cmd.x_mm, cmd.y_mm, cmd.z_mm}, c)) return false;
  // Distance each carriage travelled below its endstop, the same on the real machine.
  const auto hn = delta_homed_carriages(nominal), ha = delta_homed_carriages(actual);
  std::array<double, 3> real{};
  for (std::size_t i = 0; i < 3; ++i) real[i] = ha[i] - (hn[i] - c[i]);
  DeltaPoint p;
  if (!delta_position(actual, real, p)) return false;
  true_height_mm = p.z;
  return true;
}

double delta_probe_height(const DeltaGeometry& nominal, const DeltaGeometry& actual, double x_mm, double y_mm) {
  double z = 0;
  for (int it = 0; it < 50; ++it) {
    double h0 = 0, h1 = 0;
    const double dz = 1e-3;
    if (!delta_true_height(nominal, actual, {x_mm, y_mm, z}, h0) ||
        !delta_true_height(nominal, actual, {x_mm, y_mm, z + dz}, h1))
      throw std::runtime_error("probe point out of the delta's reach");
    const double slope = (h1 - h0) / dz;
    if (!(std::abs(slope) > 1e-6)) throw std::runtime_error("probe height model is singular here");
    const double step = h0 / slope;
    z -= step;
    if (std::abs(step) < 1e-12) return z;
  }
  return z;
}

}  // namespace tunekit::ident
