// Errors as Python exceptions carrying the command line's messages: fvm.InputError (a ValueError: a file, value or
// combination to fix, exit 1 of the CLI) and fvm.NotConvergedError (a RuntimeError: the solver did not converge,
// exit 3).

#include <pybind11/stl.h>

#include <exception>
#include <stdexcept>

#include "core/exit_codes.h"
#include "core/input_error.h"
#include "python/bindings.h"

namespace fvm::python {

void BindErrors(py::module_& m) {
  static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
  input_error.doc() =
      "Bad input: a file, value or combination to fix; the message names it, as the command line's does (its "
      "exit code 1).\n\nExample:\n    >>> try:\n    ...     fvm.read_surface('missing.x3p')\n"
      "    ... except fvm.InputError as e:\n    ...     print(e)";
  static py::exception<NotConvergedError> not_converged(m, "NotConvergedError", PyExc_RuntimeError);
  not_converged.doc() =
      "A solver stopped before it converged (the command line's exit code 3): the result must not be trusted as "
      "it is.\n\nExample:\n    >>> try:\n    ...     cal = fvm.calibrate('samples/bar17')\n"
      "    ... except fvm.NotConvergedError as e:\n    ...     print(e)";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      input_error(e.what());
    } catch (const NotConvergedError& e) {
      not_converged(e.what());
    } catch (const std::invalid_argument& e) {
      // Library checks are bad input reaching a deeper layer: the command line reads them the same way (exit 1).
      input_error(e.what());
    }
  });
}

}  // namespace fvm::python
