#pragma once
/// \file
/// The Python module `vtb` (pybind11): each part binds one piece of the C++ API and nothing
/// here reimplements a solver. The module is `vtb._vtb`; `vtb/__init__.py` re-exports it.

#include "vtb/problem/scene.hh"

#include <pybind11/pybind11.h>

namespace vtb::python {

namespace py = pybind11;

/// A scene argument: a vtb.Scene, a path (str or os.PathLike) to a TOML file, or a dict of the
/// file's tables (validated by the same reader: InputError naming the key).
Scene to_scene(const py::handle& obj);

void bind_scene(py::module_& m);      ///< Scene, the dict -> TOML bridge (scene_binding.cc)
void bind_simulation(py::module_& m); ///< Simulation: a scene you step yourself (simulation_binding.cc)
void bind_harness(py::module_& m);    ///< run, compare, study, sweep (harness_binding.cc)

} // namespace vtb::python
