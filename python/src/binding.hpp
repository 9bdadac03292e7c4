#pragma once
// What the files of the Python module share: an analysis' typed outcome kept alive for export
// (OutcomeHandle), the parsing of keyword arguments with the command line's own binding of a
// command, and the fits whose covariance a result carries.

#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <CLI/CLI.hpp>

#include "tunekit/calibration/results/context.hpp"
#include "tunekit/fitting/fit_result.hpp"

namespace tunekit::python {

namespace py = pybind11;

/// One keyword argument as the Python side passes it: the name as written in Python
/// ("step_at", "K", "T") and its values as text (empty: a flag given).
using KeywordArgument = std::pair<std::string, std::vector<std::string>>;

/// An analysis' typed outcome, kept for export to design from ("step", "freq", "shaper", ...).
struct OutcomeHandle {
  std::string command;
  std::shared_ptr<const void> outcome;
};

/// A fit of an outcome and where its JSON lies in the results (a JSON pointer, "" for the whole).
using FitAt = std::pair<std::string, const fitting::FitResult*>;

/// Parses `positional` and `keywords` with the subcommand `add_command` adds, so that a keyword is
/// the command's long option of the same name (underscores as dashes; a one-letter name may also
/// be its short option). A name the command has not, or a value it refuses: ValueError.
void parse_command(const std::function<CLI::App*(CLI::App&)>& add_command, const std::vector<std::string>& positional,
                   const std::vector<KeywordArgument>& keywords);

/// Per fit with a covariance: its JSON pointer -> (parameter names, covariance matrix as numpy).
py::dict covariances(const std::vector<FitAt>& fits);

void bind_errors(py::module_& m);
void bind_analyses(py::module_& m);
void bind_export(py::module_& m);
void bind_history(py::module_& m);

}  // namespace tunekit::python
