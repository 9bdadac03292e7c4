// An accelerometer record's checks (the median interval of its clock, the order its problems are
// reported in) and the Welch spectra of its channels computed side by side.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <span>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/ident/resonance.hpp"
#include "tunekit/ident/spectrum.hpp"

using namespace tunekit;

namespace {

// A raw file at about 3.2 kHz: `jitter` (seconds, uniform) on every time stamp, one sample
// dropped in the middle so that the record is resampled at its median interval; `wild_every`
// > 0 puts 1e200 into accel_x every that many rows, `gap_s` > 0 a gap after the first half.
std::string raw_csv(double jitter, std::size_t wild_every = 0, double gap_s = 0) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-jitter, jitter);
  std::string s = "#time,accel_x,accel_y,accel_z\n";
  const std::size_t n = 20000;
  for (std::size_t i = 0; i < n; ++i) {
    if (i == n / 2) continue;
    const double t = 100.0 + static_cast<double>(i) / 3200.0 + (jitter > 0 ? u(rng) : 0.0) + (i > n / 2 ? gap_s : 0.0);
    const double x = wild_every > 0 && i % wild_every == 0 ? 1e200 : 500 * std::sin(0.3 * static_cast<double>(i));
    s += fmt::format("{:.7f},{:.6f},{:.6f},{:.6f}\n", t, x, 200 * std::cos(0.11 * static_cast<double>(i)),
                     9800 + std::sin(0.05 * static_cast<double>(i)));
  }
  return s;
}

// The median of the time column's intervals as fitting::median takes it: the (n/2)-th smallest.
double median_interval_of(const std::string& csv) {
  const auto table = formats::parse_csv(csv, "raw.csv", {{"time"}, "time"});
  const auto& t = table.column("time").values;
  std::vector<double> dt;
  for (std::size_t i = 1; i < t.size(); ++i) dt.push_back(t[i] - t[i - 1]);
  const auto mid = dt.begin() + static_cast<std::ptrdiff_t>(dt.size() / 2);
  std::nth_element(dt.begin(), mid, dt.end());
  return *mid;
}

}  // namespace

TEST_CASE("a resampled record's rate is one over the median interval, from a steady clock and from a jittery one",
          "[resonance]") {
  // A steady clock gives a handful of distinct intervals, a jittery one thousands: both must give
  // the median of all the intervals.
  for (const double jitter : {0.0, 2e-5}) {
    INFO("jitter " << jitter);
    const std::string csv = raw_csv(jitter);
    const auto rec = ident::load_accel_csv("raw_data_x_test.csv", csv, {});
    REQUIRE(rec.sampling.resampled);
    CHECK(rec.sampling.sample_rate_hz == 1.0 / median_interval_of(csv));
  }
}

TEST_CASE("wild samples are reported before irregular sampling, as the record's checks come in that order",
          "[resonance]") {
  try {
    (void)ident::load_accel_csv("raw_data_x_test.csv", raw_csv(0, 10, 1.0), {});
    FAIL("accepted");
  } catch (const InputError& e) {
    CHECK(std::string(e.message()).find("beyond any accelerometer's range") != std::string::npos);
  }
  try {
    (void)ident::load_accel_csv("raw_data_x_test.csv", raw_csv(0, 0, 1.0), {});
    FAIL("accepted");
  } catch (const InputError& e) {
    CHECK(std::string(e.message()).find("irregular sampling") != std::string::npos);
  }
}

TEST_CASE("the Welch spectra of a record's channels side by side are each channel's own, to the bit", "[resonance]") {
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0, 1);
  std::vector<std::vector<double>> channels(3, std::vector<double>(30000));
  for (std::size_t c = 0; c < channels.size(); ++c)
    for (std::size_t i = 0; i < channels[c].size(); ++i)
      channels[c][i] = std::sin(0.02 * static_cast<double>((c + 1) * i)) + 0.1 * noise(rng) + static_cast<double>(c);
  const std::vector<std::span<const double>> views(channels.begin(), channels.end());
  for (const auto detrend : {ident::Detrend::none, ident::Detrend::constant, ident::Detrend::linear}) {
    ident::WelchOptions o = ident::klipper_welch_options();
    o.detrend = detrend;
    const auto together = ident::welch_psds(views, 3200, o);
    REQUIRE(together.size() == channels.size());
    for (std::size_t c = 0; c < channels.size(); ++c) {
      const auto alone = ident::welch_psd(channels[c], 3200, o);
      CHECK(together[c].psd == alone.psd);
      CHECK(together[c].freq_hz == alone.freq_hz);
      CHECK(together[c].segments == alone.segments);
    }
  }
}
