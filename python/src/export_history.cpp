// export and history from Python. export designs from the analyses' typed outcomes (or the
// results files its `results` option names) and goes through the command's own two steps:
// compute_export() designs and prepares every file, commit_export() writes them and the JSON
// together or not at all and prints the diff and the summary. history reads the calibration
// history (SQLite or PostgreSQL) with the history command's functions.

#include <sstream>

#include "binding.hpp"
#include "tunekit/calibration/commands/design_inputs.hpp"
#include "tunekit/calibration/commands/history_command.hpp"
#include "tunekit/cli/analysis_commands.hpp"
#include "tunekit/core/error.hpp"

namespace tunekit::python {

using namespace calibration;

namespace {

/// The design inputs of the outcomes, each under its origin (the name messages give it).
DesignInputs design_inputs_of(const std::vector<OutcomeHandle>& results, const std::vector<std::string>& origins) {
  DesignInputs inputs;
  for (std::size_t i = 0; i < results.size(); ++i) {
    const OutcomeHandle& r = results[i];
    const std::string origin = i < origins.size() ? origins[i] : r.command;
    if (r.command == "step") {
      inputs.step = step_design_input(*std::static_pointer_cast<const StepOutcome>(r.outcome), origin);
    } else if (r.command == "freq") {
      inputs.freq = freq_design_input(*std::static_pointer_cast<const FreqOutcome>(r.outcome), origin);
    } else if (r.command == "shaper") {
      for (auto& [axis, a] : shaper_design_inputs(*std::static_pointer_cast<const ShaperOutcome>(r.outcome), origin))
        inputs.axes[axis] = a;
    } else {
      throw InputError("results of '" + r.command +
                       "' cannot be designed from here (step, freq or shaper; rheo's as a results file)");
    }
    inputs.origins.push_back(origin);
  }
  return inputs;
}

/// export: (the JSON the command prints with --json, what it prints without, its exit code).
py::tuple run_export(const std::vector<OutcomeHandle>& results, const std::vector<std::string>& origins,
                     const std::vector<std::string>& positional, const std::vector<KeywordArgument>& keywords) {
  ExportOptions options;
  OutputOptions output;
  parse_command([&](CLI::App& app) { return cli::add_export_command(app, options, output); }, positional, keywords);
  if (!results.empty() && !options.results.empty())
    throw InputError("give the results as result objects or as results files, not both");
  const DesignInputs inputs = design_inputs_of(results, origins);
  std::ostringstream out, err;
  std::string json;
  int code = 0;
  {
    py::gil_scoped_release released;
    const ExportOutcome outcome = results.empty() ? compute_export(options) : compute_export(options, inputs);
    CliContext ctx{out, err};
    code = commit_export(outcome, output, ctx);
    json = prepare_emission(to_envelope(outcome), output).text;
  }
  return py::make_tuple(json, out.str(), code);
}

template <class Compute>
std::string history_json(const HistoryOptions& options, const Compute& compute) {
  py::gil_scoped_release released;
  return prepare_emission(to_envelope(compute(options)), OutputOptions{}).text;
}

HistoryOptions history_options(const std::string& db, const std::vector<std::string>& machines,
                               const std::vector<std::string>& quantities, std::int64_t record_id) {
  HistoryOptions o;
  o.db = db;
  o.machines = machines;
  o.quantities = quantities;
  o.record_id = record_id;
  return o;
}

}  // namespace

void bind_export(py::module_& m) { m.def("export", run_export); }

void bind_history(py::module_& m) {
  m.def("history_list", [](const std::string& db, const std::vector<std::string>& machines) {
    return history_json(history_options(db, machines, {}, 0), compute_history_list);
  });
  m.def("history_show", [](const std::string& db, std::int64_t record_id) {
    return history_json(history_options(db, {}, {}, record_id), compute_history_show);
  });
  m.def("history_trend", [](const std::string& db, const std::vector<std::string>& machines,
                            const std::vector<std::string>& quantities) {
    return history_json(history_options(db, machines, quantities, 0), compute_history_trend);
  });
}

}  // namespace tunekit::python
