// Every analysis command as a function of _tunekit: f(positional, keywords[, csv]) -> (the JSON
// the command prints with --json, {pointer: (names, covariance)}, the typed outcome). The options
// are parsed by the command line's own binding of the command and the work is the calibration
// library's compute function, so the results are the command's, number for number. The fit runs
// without the GIL. A new analysis is one bind_analysis() line (and its add_x_command).

#include <sstream>
#include <type_traits>

#include "binding.hpp"
#include "tunekit/calibration/results/input_digest.hpp"
#include "tunekit/cli/analysis_commands.hpp"

namespace tunekit::python {

using namespace calibration;

namespace {

/// The outcome's JSON as the command prints it, with the fits' covariances and the outcome.
template <class Outcome>
py::tuple analysis_answer(const char* command, std::shared_ptr<const Outcome> outcome, std::string text,
                          const std::vector<FitAt>& fits) {
  return py::make_tuple(std::move(text), covariances(fits), OutcomeHandle{command, std::move(outcome)});
}

/// Runs `compute` on the parsed options without the GIL; the envelope's text as `tunekit ... --json` prints it.
template <class Options, class Compute>
auto compute_released(const Options& options, const Compute& compute) {
  using Outcome = std::decay_t<std::invoke_result_t<Compute, const Options&>>;
  py::gil_scoped_release released;
  auto outcome = std::make_shared<const Outcome>(compute(options));
  std::string text = prepare_emission(to_envelope(*outcome), OutputOptions{}).text;
  return std::make_pair(std::move(outcome), std::move(text));
}

template <class Options>
Options parsed_options(CLI::App* (*add)(CLI::App&, Options&, OutputOptions&),
                       const std::vector<std::string>& positional, const std::vector<KeywordArgument>& keywords) {
  Options options;
  OutputOptions output;
  parse_command([&](CLI::App& app) { return add(app, options, output); }, positional, keywords);
  return options;
}

/// Binds _tunekit.<command>(positional, keywords).
template <class Options, class Compute, class Fits>
void bind_analysis(py::module_& m, const char* command, CLI::App* (*add)(CLI::App&, Options&, OutputOptions&),
                   Compute compute, Fits fits) {
  m.def(command, [command, add, compute, fits](const std::vector<std::string>& positional,
                                               const std::vector<KeywordArgument>& keywords) {
    const Options options = parsed_options(add, positional, keywords);
    auto [outcome, text] = compute_released(options, compute);
    return analysis_answer(command, outcome, std::move(text), fits(*outcome));
  });
}

template <class Outcome>
std::vector<FitAt> no_fits(const Outcome&) {
  return {};
}

std::vector<FitAt> step_fits(const StepOutcome& o) {
  std::vector<FitAt> fits;
  if (o.analysis.pooled) fits.emplace_back("/pooled", &*o.analysis.pooled);
  for (std::size_t i = 0; i < o.analysis.steps.size(); ++i)
    if (o.analysis.steps[i].fit) fits.emplace_back("/steps/" + std::to_string(i), &*o.analysis.steps[i].fit);
  return fits;
}

std::vector<FitAt> freq_fits(const FreqOutcome& o) {
  std::vector<FitAt> fits{{"/fit", o.reported_fit()}};
  if (o.tf_fit) fits.emplace_back("/tf_fit", &*o.tf_fit);
  if (o.oe_fit) fits.emplace_back("/tf_oe_fit", &*o.oe_fit);
  return fits;
}

std::vector<FitAt> rheo_fits(const RheoOutcome& o) {
  std::vector<FitAt> fits{{"", &o.fit}};
  for (std::size_t i = 0; i < o.power_laws.size(); ++i)
    fits.emplace_back("/power_law/fits/" + std::to_string(i), &o.power_laws[i].fit);
  return fits;
}

std::vector<FitAt> nozzle_fits(const NozzleOutcome& o) {
  return o.fit ? std::vector<FitAt>{{"", &o.fit->fit}} : std::vector<FitAt>{};
}

std::vector<FitAt> thermal_fits(const ThermalOutcome& o) { return {{"", &o.fit.fit}}; }

/// step on a table already in memory: `csv` is the text formats/csv reads, named `name`.
void bind_step_in_memory(py::module_& m) {
  m.def("step_csv", [](const std::vector<std::string>& positional, const std::vector<KeywordArgument>& keywords,
                       const std::string& name, std::string csv) {
    const StepOptions options = parsed_options(cli::add_step_command, positional, keywords);
    const InputFile file = InputFile::from_bytes(name, std::move(csv));
    auto [outcome, text] =
        compute_released(options, [&file](const StepOptions& o) { return compute_step(o, file, nullptr); });
    return analysis_answer("step", outcome, std::move(text), step_fits(*outcome));
  });
}

}  // namespace

void bind_analyses(py::module_& m) {
  py::class_<OutcomeHandle>(m, "Outcome").def_readonly("command", &OutcomeHandle::command);
  bind_analysis(
      m, "step", cli::add_step_command, [](const StepOptions& o) { return compute_step(o); }, step_fits);
  bind_step_in_memory(m);
  bind_analysis(m, "freq", cli::add_freq_command, compute_freq, freq_fits);
  bind_analysis(m, "rheo", cli::add_rheo_command, compute_rheo, rheo_fits);
  bind_analysis(m, "nozzle", cli::add_nozzle_command, compute_nozzle, nozzle_fits);
  bind_analysis(m, "resonance", cli::add_resonance_command, compute_resonance, no_fits<ResonanceOutcome>);
  bind_analysis(m, "shaper", cli::add_shaper_command, compute_shaper, no_fits<ShaperOutcome>);
  bind_analysis(m, "belts", cli::add_belts_command, compute_belts, no_fits<BeltsOutcome>);
  bind_analysis(m, "delta", cli::add_delta_command, compute_delta, no_fits<DeltaOutcome>);
  bind_analysis(m, "thermal", cli::add_thermal_command, compute_thermal, thermal_fits);
  bind_analysis(
      m, "linewidth", cli::add_linewidth_command,
      [](const LinewidthOptions& o) {
        std::ostringstream progress;  // the command's progress lines on stderr
        return compute_linewidth(o, progress);
      },
      no_fits<LinewidthOutcome>);
  bind_analysis(
      m, "overshoot", cli::add_overshoot_command, [](const OvershootOptions& o) { return compute_overshoot(o); },
      no_fits<OvershootOutcome>);
}

}  // namespace tunekit::python
