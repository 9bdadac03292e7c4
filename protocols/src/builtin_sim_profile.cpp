// The machine profile of tunekit's built-in simulated printer (`--machine sim`).
#include "tunekit/machine/machine_profile.hpp"
#include "tunekit/protocols/runner.hpp"

namespace tunekit::protocols {
namespace {

// Same content as datasets/machines/sim.toml (tests check that they agree).
constexpr const char* kSimProfile = R"(# Machine profile of tunekit's built-in simulated printer (tunekit-sim).
[machine]
name = "tunekit simulated printer"
kinematics = "cartesian"
firmware = "marlin"

[axes.x]
min_mm = 0
max_mm = 220
max_velocity_mm_s = 300
max_accel_mm_s2 = 10000

[axes.y]
min_mm = 0
max_mm = 220
max_velocity_mm_s = 300
max_accel_mm_s2 = 10000

[axes.z]
min_mm = 0
max_mm = 250
max_velocity_mm_s = 15
max_accel_mm_s2 = 200

[extruder]
filament_diameter_mm = 1.75
nozzle_diameter_mm = 0.4
max_flow_mm3_s = 15
max_velocity_mm_s = 60
max_accel_mm_s2 = 5000

[print]
max_accel_mm_s2 = 3000
line_width_mm = 0.45
layer_height_mm = 0.2
speed_mm_s = 60

[temperature]
hotend_max_c = 280
bed_max_c = 110
heaters_off_on_abort = true

[sensors]
accelerometer = true
accelerometer_rate_hz = 3200
load_cell = true
filament_encoder = false
camera = false

# The firmware's own settings the protocols change for a test and restore after it. The
# simulated printer has 160 steps/mm on X and Y (enough steps for Marlin's sweep to 100 Hz
# above MIN_STEPS_PER_SEGMENT) and no input shaper configured.
[firmware_state]
steps_per_mm_x = 160
steps_per_mm_y = 160
)";

}  // namespace

machine::MachineProfile builtin_sim_profile() {
  return machine::parse_machine_profile(kSimProfile, "<built-in simulated printer profile>");
}

}  // namespace tunekit::protocols
