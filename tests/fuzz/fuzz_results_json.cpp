// tunekit's results JSON read back: parsing with located errors, the envelope check, the
// --require evaluation and the HTML report built from it.
#include "fuzz_common.hpp"
#include "tunekit/calibration/presentation/report.hpp"
#include "tunekit/calibration/results/requirements.hpp"
#include "tunekit/calibration/results/results_json.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > 65536) return -1;
  const std::string text(tunekit::fuzz::as_text(data, size));
  tunekit::fuzz::expect_result_or_error([&] {
    const auto j = tunekit::calibration::parse_results_json(text, "fuzz.json");
    tunekit::calibration::check_results_envelope(j, text, "fuzz.json");
    for (const char* req : {"tau_s<0.6", "x.freq_hz>=40", "n<0.5"})
      tunekit::fuzz::expect_result_or_error([&] {
        tunekit::calibration::evaluate_requirement(tunekit::calibration::parse_requirement(req),
                                                   j.contains("results") ? j["results"] : j);
      });
    // The record read back (a located InputError for members of an unexpected type) and its report.
    tunekit::calibration::build_report_html(tunekit::calibration::record_from_json(j, {}, "fuzz.json"), {});
  });
  return 0;
}
