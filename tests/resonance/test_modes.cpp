// Modal identification from synthetic Klipper-style sweeps with known modes.
#include <catch2/catch.hpp>

#include <cmath>

#include "synth_sweep.hpp"
#include "tunekit/ident/resonance.hpp"

using namespace tunekit;
using tunekit::test::SweepSpec;
using tunekit::test::SynthMode;

namespace {

ident::AccelRecord to_record(const test::SynthRecord& s, double fs, bool with_cmd, char axis = 'x') {
  ident::AccelRecord r;
  r.path = "synthetic";
  r.axis = axis;
  r.channel_names = {"accel_x", "accel_y", "accel_z"};
  r.channels = {s.ax, s.ay, s.az};
  if (with_cmd) r.excitation = s.cmd;
  r.sampling.sample_rate_hz = fs;
  r.sampling.samples = s.t.size();
  return r;
}

void check_modes(const ident::AxisModes& m, const std::vector<SynthMode>& truth) {
  REQUIRE(m.modes.size() == truth.size());
  for (std::size_t k = 0; k < truth.size(); ++k) {
    const auto& e = m.modes[k];
    INFO("mode " << k << ": f " << e.freq_hz << " [" << e.freq_ci95_lo << ", " << e.freq_ci95_hi << "] truth "
                 << truth[k].freq_hz << "; zeta " << e.zeta << " [" << e.zeta_ci95_lo << ", " << e.zeta_ci95_hi
                 << "] truth " << truth[k].zeta << " method " << m.method);
    CHECK(std::abs(e.freq_hz / truth[k].freq_hz - 1) < 0.01);
    CHECK(std::abs(e.zeta / truth[k].zeta - 1) < 0.20);
    CHECK(e.freq_ci95_lo <= truth[k].freq_hz);
    CHECK(e.freq_ci95_hi >= truth[k].freq_hz);
    CHECK(e.zeta_ci95_lo <= truth[k].zeta);
    CHECK(e.zeta_ci95_hi >= truth[k].zeta);
    CHECK(e.freq_ci95_hi > e.freq_ci95_lo);
  }
}

}  // namespace

TEST_CASE("two modes from a Klipper-style sweep PSD: frequency within 1 %, damping within 20 %, intervals cover",
          "[resonance]") {
  const std::vector<SynthMode> truth = {{42.0, 0.05, 1.0}, {77.0, 0.08, 0.6}};
  for (unsigned seed : {1u, 2u, 3u}) {
    SweepSpec spec;
    spec.seed = seed;
    const auto s = test::synth_sweep(truth, spec);
    const auto sp = ident::record_spectrum(to_record(s, spec.sample_rate_hz, false), ident::klipper_welch_options());
    const auto m = ident::identify_modes(sp, {});
    INFO("seed " << seed);
    check_modes(m, truth);
    CHECK(m.method == "psd");
  }
}

TEST_CASE("lightly damped single mode with a direct term", "[resonance]") {
  const std::vector<SynthMode> truth = {{55.0, 0.03, 0.8}};
  SweepSpec spec;
  spec.direct = 0.3;
  spec.seed = 7;
  const auto s = test::synth_sweep(truth, spec);
  const auto sp = ident::record_spectrum(to_record(s, spec.sample_rate_hz, false), ident::klipper_welch_options());
  const auto m = ident::identify_modes(sp, {});
  check_modes(m, truth);
}

TEST_CASE("with the commanded acceleration the FRF is fitted", "[resonance]") {
  const std::vector<SynthMode> truth = {{42.0, 0.05, 1.0}, {77.0, 0.08, 0.6}};
  SweepSpec spec;
  spec.seed = 11;
  const auto s = test::synth_sweep(truth, spec);
  const auto sp = ident::record_spectrum(to_record(s, spec.sample_rate_hz, true), ident::klipper_welch_options());
  REQUIRE(sp.frf.has_value());
  const auto m = ident::identify_modes(sp, {});
  CHECK(m.method == "frf");
  check_modes(m, truth);
}
