#pragma once
// Linear delta kinematics (three vertical towers, carriages joined to the effector by
// diagonal rods) and the probe-height model that firmware auto-calibrations fit.
// After Brown, "Delta Printer Project Report", La Trobe University, 2013, with the
// parameter conventions of RepRapFirmware's linear delta kinematics (which Klipper's
// [printer]/[stepper_*] delta options and Marlin's M665/M666 map onto).
//
// Units: millimetres for lengths, degrees for angles. Coordinates: X right, Y towards the
// back, Z up, origin at the bed centre on the bed surface.
//
//   tower i at angle_deg[i] (nominal 210, 330, 90 for towers A/X, B/Y, C/Z), distance
//   radius_mm from the centre: (R cos a_i, R sin a_i).
//   carriage height for nozzle (x, y, z):  c_i = z + sqrt(L_i^2 - (x-tx_i)^2 - (y-ty_i)^2)
//                                                + x tilt_x + y tilt_y
//   carriage height when homed (at its endstop): c_home_i = H + sqrt(L_i^2 - R^2) + e_i
// where H is the homed height (nozzle height at the centre when every e_i is 0) and e_i
// the endstop adjustment (positive: that carriage stops higher). Klipper's stepper
// position_endstop is H + e_i; Marlin stores e_i - max(e) (all <= 0) and H + max(e).
#include <array>

namespace tunekit::ident {

struct DeltaGeometry {
  double radius_mm = 0;            ///< delta radius R (tower column to centre, minus effector offsets)
  std::array<double, 3> rod_mm{};  ///< diagonal rod length L per tower
  std::array<double, 3> angle_deg{210.0, 330.0, 90.0};  ///< tower angle about the centre
  std::array<double, 3> endstop_mm{};                   ///< endstop adjustment e per tower
  double homed_height_mm = 0;                           ///< H
  double tilt_x = 0;                                    ///< bed tilt: dz per mm of x (fraction, RRF M666 A / 100)
  double tilt_y = 0;                                    ///< bed tilt: dz per mm of y (fraction, RRF M666 B / 100)
};

/// Nominal tower angles (degrees) of towers A, B, C.
inline constexpr std::array<double, 3> kDeltaNominalAngles{210.0, 330.0, 90.0};

struct DeltaPoint {
  double x = 0, y = 0, z = 0;  ///< mm
};

/// Inverse kinematics: carriage heights (mm above the bed plane) for the nozzle at p.
/// Returns false when a rod cannot reach (the point is outside the machine).
bool delta_carriages(const DeltaGeometry& g, const DeltaPoint& p, std::array<double, 3>& carriages);
/// Forward kinematics: the nozzle position for carriage heights (the solution below the
/// carriages). Returns false when the rods cannot meet.
bool delta_position(const DeltaGeometry& g, const std::array<double, 3>& carriages, DeltaPoint& p);
/// How the height of a forward solution moves with the geometry. With P_t the joint of tower t's
/// rod on its carriage (tower column at the carriage height, mm), L_t the rod lengths and q the
/// nozzle before the bed tilt, small changes dP_t, dL_t move the reported height by
///   dz = sum_t weight[t] ((q - P_t) . dP_t + L_t dL_t),
/// the rods' constraints |q - P_t| = L_t differentiated (implicit function theorem); a tilt
/// change moves it by -x dtilt_x - y dtilt_y (x, y of the solution, tilts as fractions).
struct DeltaHeightSensitivity {
  std::array<double, 3> weight{};                       ///< 1/mm
  std::array<std::array<double, 3>, 3> joint_offset{};  ///< q - P_t (x, y, z), mm
};

/// Forward kinematics of one geometry for many carriage heights: the tower positions (mm,
/// from the radius and the tower angles) are computed once, not once per point.
class DeltaForward {
 public:
  explicit DeltaForward(const DeltaGeometry& g);
  /// As delta_position(g, carriages, p); when `sensitivity` is not null it is filled too (false
  /// also when the rods are coplanar with the nozzle, where the height does not move smoothly).
  bool position(const std::array<double, 3>& carriages, DeltaPoint& p,
                DeltaHeightSensitivity* sensitivity = nullptr) const;

 private:
  DeltaGeometry g_;
  std::array<std::array<double, 2>, 3> towers_{};
};
/// Carriage heights when homed (carriages at their endstops).
std::array<double, 3> delta_homed_carriages(const DeltaGeometry& g);

/// One probe point as a firmware reports it (G30 S-1): the commanded (x, y) and the
/// commanded height z at which the probe triggered, all under the firmware's geometry.
struct DeltaProbe {
  double x_mm = 0, y_mm = 0, z_mm = 0;
};

/// The height the nozzle truly has above the bed plane when a firmware running `nominal`
/// commands (x, y, z) and the machine's real geometry is `actual` (homed, so the carriages
/// travel the same distance below their endstops in both). A probe trigger at commanded z
/// means this is 0 for a flat bed. Returns false when out of reach.
bool delta_true_height(const DeltaGeometry& nominal, const DeltaGeometry& actual, const DeltaProbe& commanded,
                       double& true_height_mm);

/// The probe height a firmware running `nominal` measures at (x, y) on the flat bed of a
/// machine whose real geometry is `actual`: the commanded z at which the nozzle touches
/// z = 0 (solved by Newton's method). Throws std::runtime_error when out of reach.
double delta_probe_height(const DeltaGeometry& nominal, const DeltaGeometry& actual, double x_mm, double y_mm);

}  // namespace tunekit::ident
