// Keyword arguments -> the command line's own parsing of a command (tunekit/cli/
// analysis_commands.hpp), and the covariances a result carries.

#include <algorithm>

#include <pybind11/numpy.h>

#include "binding.hpp"

namespace tunekit::python {

namespace {

/// The option `name` (a Python keyword) stands for: --name-with-dashes, --name, or -n.
std::string option_for_keyword(const CLI::App& sub, const std::string& name) {
  std::string dashed = name;
  std::replace(dashed.begin(), dashed.end(), '_', '-');
  for (const std::string& flag : {"--" + dashed, "--" + name, "-" + name})
    if ((flag.size() == 2 || flag.rfind("--", 0) == 0) && sub.get_option_no_throw(flag) != nullptr) return flag;
  throw py::value_error("unknown option '" + name + "' for 'tunekit " + sub.get_name() + "'");
}

}  // namespace

void parse_command(const std::function<CLI::App*(CLI::App&)>& add_command, const std::vector<std::string>& positional,
                   const std::vector<KeywordArgument>& keywords) {
  CLI::App app;
  CLI::App* sub = add_command(app);
  std::vector<std::string> args{sub->get_name()};
  for (const auto& [name, values] : keywords) {
    const std::string flag = option_for_keyword(*sub, name);
    if (values.empty()) args.push_back(flag);
    for (const auto& v : values) {
      args.push_back(flag);
      args.push_back(v);
    }
  }
  if (!positional.empty()) args.emplace_back("--");
  args.insert(args.end(), positional.begin(), positional.end());
  std::reverse(args.begin(), args.end());  // CLI11 parses from the back
  try {
    app.parse(args);
  } catch (const CLI::ParseError& e) {
    throw py::value_error(std::string(e.what()));
  }
}

py::dict covariances(const std::vector<FitAt>& fits) {
  py::dict out;
  for (const auto& [pointer, fit] : fits) {
    if (fit == nullptr || fit->covariance.empty()) continue;
    const auto n = static_cast<py::ssize_t>(fit->params.size());
    py::array_t<double> matrix({n, n});
    std::copy(fit->covariance.begin(), fit->covariance.end(), matrix.mutable_data());
    py::list names;
    for (const auto& p : fit->params) names.append(p.name);
    out[py::str(pointer)] = py::make_tuple(names, matrix);
  }
  return out;
}

}  // namespace tunekit::python
