#include "bindings.hh"

#include "vtb/base/atomic_file.hh"
#include "vtb/base/input_error.hh"

PYBIND11_MODULE(_vtb, m) {
  namespace py = pybind11;
  m.doc() = "vtb, the Voigt deformation testbed: scenes, a simulation you step, and the harness";
  // Bad input raises vtb.InputError, whose text is the CLI's error line after "vtb: error: ";
  // a folder or disk that fails raises vtb.IoError (the CLI's "vtb: I/O error: ").
  py::register_exception<vtb::InputError>(m, "InputError", PyExc_ValueError);
  py::register_exception<vtb::IoError>(m, "IoError", PyExc_OSError);
  vtb::python::bind_scene(m);
  vtb::python::bind_simulation(m);
  vtb::python::bind_harness(m);
}
