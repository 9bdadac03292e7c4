// The tunekit Python module's native part, _tunekit: the version, the errors and every binding
// (the package python/tunekit wraps them in result objects; docs/python.md).

#include <pybind11/pybind11.h>

#include "binding.hpp"
#include "tunekit/core/version.hpp"

PYBIND11_MODULE(_tunekit, m) {
  namespace tp = tunekit::python;
  m.doc() = "tunekit's calibration library: the analyses, export and history (see the tunekit package)";
  m.attr("__version__") = tunekit::core::kVersion;
  tp::bind_errors(m);
  tp::bind_analyses(m);
  tp::bind_export(m);
  tp::bind_history(m);
}
