// tunekit's errors as Python exceptions, with the one line the command prints after
// "tunekit: error: ": bad input (InputError, a keyword the command has not) is ValueError, a fit
// that failed is tunekit.FitError, a machine or transport failure tunekit.MachineError (both
// RuntimeError).

#include <string>

#include "binding.hpp"
#include "tunekit/core/error.hpp"

namespace tunekit::python {

namespace {
std::string error_line(const Error& e) {
  return e.location().empty() ? e.message() : e.location() + ": " + e.message();
}
}  // namespace

void bind_errors(py::module_& m) {
  static py::exception<FitError> fit_error(m, "FitError", PyExc_RuntimeError);
  static py::exception<MachineError> machine_error(m, "MachineError", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const FitError& e) {
      fit_error(error_line(e).c_str());
    } catch (const MachineError& e) {
      machine_error(error_line(e).c_str());
    } catch (const Error& e) {
      PyErr_SetString(PyExc_ValueError, error_line(e).c_str());
    }
  });
}

}  // namespace tunekit::python
