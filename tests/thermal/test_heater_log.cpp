// Heater logs read into a thermal record: Klipper's klippy.log Stats lines (the heater's part as
// klippy/extras/heaters.py Heater.stats prints it, "%s: target=%.0f temp=%.1f pwm=%.3f", only
// while the heater is active) and Marlin's temperature reports (@ the 0-127 soft-PWM amount,
// Marlin/src/module/temperature.cpp). Hostile inputs get one clear message.
#include <algorithm>
#include <catch2/catch.hpp>
#include <string>

#include "test_support.hpp"

#include "tunekit/core/error.hpp"
#include "tunekit/formats/heater_log.hpp"
#include "tunekit/ident/heater_log_record.hpp"

using namespace tunekit;
using Catch::Matchers::Contains;

// The file's helpers in a namespace of their own: the test areas are unity builds.
namespace test_heater_log {

std::string stats(double t, const std::string& heaters) {
  return "Stats " + std::to_string(t).substr(0, std::to_string(t).find('.') + 2) +
         ": gcodein=0  mcu: mcu_awake=0.005 mcu_task_avg=0.000028 bytes_write=1061 freq=72000317  " + heaters +
         " sysload=0.00 cputime=2.368 memavail=261440 print_time=292.793 buffer_time=0.000 print_stall=0\n";
}

}  // namespace test_heater_log

using test_heater_log::stats;

TEST_CASE("klippy.log: the extruder's target, temperature and PWM from each Stats line") {
  std::string log = "Starting Klippy...\nStart printer at Fri Dec  6 14:28:53 2024 (1733516933.1 2014.0)\n";
  log += stats(2016.5, "heater_bed: target=60 temp=21.5 pwm=1.000");  // the extruder idle and cold: absent
  log += stats(2017.5, "heater_bed: target=60 temp=22.0 pwm=1.000 extruder: target=210 temp=20.7 pwm=1.000");
  log += stats(2018.5, "heater_bed: target=60 temp=22.6 pwm=1.000 extruder: target=210 temp=23.9 pwm=0.874");
  log += "webhooks client 1: New connection\n";
  log += stats(2019.5, "extruder: target=210 temp=28.4 pwm=0.512 extruder1: target=0 temp=51.0 pwm=0.000");
  const auto h = formats::read_klippy_heater_log(log);
  REQUIRE(h.t_s.size() == 3);
  CHECK(h.lines_read == 4);
  CHECK(h.lines_skipped == 1);
  CHECK(h.t_s[0] == Approx(2017.5));
  CHECK(h.target_c[1] == Approx(210));
  CHECK(h.temp_c[2] == Approx(28.4));
  CHECK(h.duty[1] == Approx(0.874));
  // extruder1 is its own heater, not read as the extruder.
  const auto e1 = formats::read_klippy_heater_log(log, "extruder1");
  REQUIRE(e1.t_s.size() == 1);
  CHECK(e1.temp_c[0] == Approx(51.0));

  const auto rec = ident::thermal_record_from_heater_log(h, ident::heated_run(h));
  CHECK(rec.t_s == std::vector<double>{0.0, 1.0, 2.0});
  CHECK(rec.heater_duty == std::vector<double>{1.0, 0.874, 0.512});
  CHECK(rec.fan_duty.empty());  // the part fan is not in Stats
  CHECK(rec.feed_mm_s.empty());
  CHECK(rec.target_c.size() == 3);
}

TEST_CASE("klippy.log: a restart or a long gap starts a new run, the longest heated run is fitted") {
  std::string log;
  for (int i = 0; i < 5; ++i) log += stats(5000.0 + i, "extruder: target=0 temp=60.0 pwm=0.000");
  log += "Start printer at Sat Dec  7 09:00:00 2024 (1733562000.0 12.0)\n";  // the host rebooted: time resets
  for (int i = 0; i < 4; ++i) log += stats(12.5 + i, "extruder: target=200 temp=30.0 pwm=1.000");
  for (int i = 0; i < 2; ++i) log += stats(100.5 + i, "extruder: target=200 temp=199.0 pwm=0.300");  // gap of 85 s
  const auto h = formats::read_klippy_heater_log(log);
  const auto runs = formats::heater_runs(h);
  REQUIRE(runs.size() == 3);
  CHECK(runs[1].begin == 5);
  CHECK(runs[1].end == 9);
  const auto best = ident::heated_run(h);
  CHECK(best.begin == 5);  // the run without a target is longer but not heated
  CHECK(ident::thermal_record_from_heater_log(h, best).t_s.back() == Approx(3.0));
}

TEST_CASE("klippy.log: truncated lines are skipped, hostile files refused with the reason") {
  std::string log = stats(10.5, "extruder: target=210 temp=100.0 pwm=0.700");
  log += "Stats 11.5: gcodein=0  mcu: mcu_awake=0.005 extruder: target=210 te";  // cut mid-line, no newline
  const auto h = formats::read_klippy_heater_log(log);
  CHECK(h.t_s.size() == 1);
  CHECK(h.lines_skipped == 1);

  CHECK_THROWS_WITH(formats::read_klippy_heater_log("Starting Klippy...\nno stats here\n"),
                    Contains("no Klipper \"Stats\" line"));
  CHECK_THROWS_WITH(formats::read_klippy_heater_log(stats(1.5, "heater_bed: target=60 temp=59.0 pwm=0.2")),
                    Contains("the log has heater_bed"));
  CHECK_THROWS_WITH(formats::read_klippy_heater_log(stats(1.5, "heater_bed: target=60 temp=59.0 pwm=0.2"), "extruder"),
                    Contains("only while it has a target"));
  // pwm outside [0, 1] is not Klipper's: skipped, and then nothing is left.
  CHECK_THROWS_AS(formats::read_klippy_heater_log(stats(1.5, "extruder: target=60 temp=59.0 pwm=7")), InputError);
  // A heater that never had a target gives no heat-up to fit.
  const auto cold = formats::read_klippy_heater_log(stats(1.5, "extruder: target=0 temp=80.0 pwm=0.000"));
  CHECK_THROWS_WITH(ident::heated_run(cold), Contains("never given a target"));
}

TEST_CASE("Marlin temperature reports: @ is the 0-127 soft-PWM amount, lines interval_s apart") {
  const std::string text =
      "echo:busy: processing\n"
      " T:25.3 /210.0 B:24.9 /0.0 @:127 B@:0\n"
      "ok T:31.0 /210.0 B:24.9 /0.0 @:127 B@:0\n"
      " T:40.2 /210.0 B:25.0 /0.0 @:64 B@:0\n"
      " T:44.0 /210.0 B:25.0";  // truncated: no power
  const auto h = formats::read_marlin_temperature_reports(text, 2.0);
  REQUIRE(h.t_s.size() == 3);
  CHECK(h.t_s[2] == Approx(4.0));
  CHECK(h.duty[0] == Approx(1.0));
  CHECK(h.duty[2] == Approx(64.0 / 127.0));
  CHECK(h.target_c[1] == Approx(210.0));
  CHECK(h.lines_skipped == 1);
  // Two hot ends: T1 and @1.
  const auto t1 = formats::read_marlin_temperature_reports(
      " T:200.0 /200.0 T0:200.0 /200.0 T1:150.5 /180.0 @:30 @0:30 @1:100\n", 1.0, "T1");
  REQUIRE(t1.t_s.size() == 1);
  CHECK(t1.temp_c[0] == Approx(150.5));
  CHECK(t1.duty[0] == Approx(100.0 / 127.0));
  CHECK_THROWS_WITH(formats::read_marlin_temperature_reports(" T:25.3 /0.0 B:24.9 /0.0\n", 1.0), Contains("power '@'"));
  CHECK_THROWS_AS(formats::read_marlin_temperature_reports(text, 0.0), InputError);
}

TEST_CASE("A real klippy.log heat-up (datasets/thermal/klippy_cetus3d) is read into a record") {
  // An excerpt of a public printer's klippy.log (PROVENANCE.md beside it): the extruder heated
  // from 16 degC to 230 degC at its max_power 0.7, held there, then cooled to 50 degC, where
  // Klipper stops printing it.
  const auto h = formats::read_klippy_heater_log(
      tunekit::test::read_text(tunekit::test::dataset("thermal/klippy_cetus3d/klippy-heatup.log")));
  CHECK(h.lines_read == 890);
  CHECK(h.lines_skipped == 0);
  REQUIRE(formats::heater_runs(h).size() == 1);
  const auto rec = ident::thermal_record_from_heater_log(h, ident::heated_run(h));
  REQUIRE(rec.t_s.size() == 890);
  CHECK(rec.t_s.back() == Approx(7665.2 - 6775.5).margin(1e-9));  // its first and last Stats times
  CHECK(rec.target_c[65] == Approx(230));
  CHECK(rec.target_c[64] == Approx(0));
  CHECK(rec.heater_duty[65] == Approx(0.7));  // max_power: Klipper's pwm never exceeds it
  CHECK(*std::max_element(rec.heater_duty.begin(), rec.heater_duty.end()) == Approx(0.7));
  CHECK(*std::max_element(rec.temp_c.begin(), rec.temp_c.end()) == Approx(233.3));
  CHECK(rec.temp_c.back() == Approx(50.0));
  CHECK(rec.fan_duty.empty());
  // The log's other heaters are its own: extruder1 heated alongside, the bed to 60 degC.
  const auto e1 = formats::read_klippy_heater_log(
      tunekit::test::read_text(tunekit::test::dataset("thermal/klippy_cetus3d/klippy-heatup.log")), "extruder1");
  CHECK(e1.t_s.size() > 100);
  CHECK(*std::max_element(e1.target_c.begin(), e1.target_c.end()) == Approx(230));
}
