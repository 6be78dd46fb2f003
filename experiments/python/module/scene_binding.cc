#include "bindings.hh"

#include "vtb/base/input_error.hh"

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>
#include <toml++/toml.h>

#include <sstream>

namespace vtb::python {

namespace {

/// One Python value as a TOML node: bool, int, float, str, os.PathLike, a list or tuple (an
/// array; a list of dicts is an array of tables, [[fix]]), a dict (a table), or anything with
/// tolist() (numpy arrays and scalars). `key` names the value in the error for anything else.
toml::table to_table(const py::dict& d, const std::string& where);

void insert(toml::array& arr, const py::handle& v, const std::string& key);

template <class Put> void put_value(const py::handle& v, const std::string& key, Put&& put) {
  if (py::isinstance<py::bool_>(v))
    put(toml::value<bool>(v.cast<bool>()));
  else if (py::isinstance<py::int_>(v))
    put(toml::value<int64_t>(v.cast<int64_t>()));
  else if (py::isinstance<py::float_>(v))
    put(toml::value<double>(v.cast<double>()));
  else if (py::isinstance<py::str>(v))
    put(toml::value<std::string>(v.cast<std::string>()));
  else if (py::hasattr(v, "__fspath__"))
    put(toml::value<std::string>(py::str(v.attr("__fspath__")()).cast<std::string>()));
  else if (py::isinstance<py::dict>(v))
    put(to_table(v.cast<py::dict>(), key));
  else if (py::isinstance<py::list>(v) || py::isinstance<py::tuple>(v)) {
    toml::array arr;
    for (const auto& x : v) insert(arr, x, key);
    put(std::move(arr));
  } else if (py::hasattr(v, "tolist"))
    put_value(v.attr("tolist")(), key, put);
  else
    throw InputError("<dict>: " + key + ": a value of type " +
                     py::str(v.get_type().attr("__name__")).cast<std::string>() +
                     " is not a TOML value (bool, int, float, str, list, dict)");
}

void insert(toml::array& arr, const py::handle& v, const std::string& key) {
  put_value(v, key, [&](auto&& node) { arr.push_back(std::forward<decltype(node)>(node)); });
}

toml::table to_table(const py::dict& d, const std::string& where) {
  toml::table t;
  for (const auto& [k, v] : d) {
    if (!py::isinstance<py::str>(k)) throw InputError("<dict>: " + where + ": keys must be strings");
    const std::string key = k.cast<std::string>();
    const std::string path = where.empty() ? key : where + "." + key;
    if (v.is_none()) continue; // None: the key is absent
    put_value(v, path, [&](auto&& node) { t.insert_or_assign(key, std::forward<decltype(node)>(node)); });
  }
  return t;
}

} // namespace

std::string dict_to_toml(const py::dict& d) {
  std::ostringstream os;
  os << to_table(d, "");
  return os.str();
}

Scene to_scene(const py::handle& obj) {
  if (py::isinstance<Scene>(obj)) return obj.cast<Scene>();
  if (py::isinstance<py::dict>(obj))
    return parse_scene(dict_to_toml(obj.cast<py::dict>()), "<dict>", std::filesystem::current_path());
  if (py::isinstance<py::str>(obj) || py::hasattr(obj, "__fspath__"))
    return read_scene(obj.cast<std::filesystem::path>());
  throw InputError("a scene is a vtb.Scene, a path to a .toml file or a dict, not a " +
                   py::str(obj.get_type().attr("__name__")).cast<std::string>());
}

void bind_scene(py::module_& m) {
  py::class_<Scene>(m, "Scene", R"(A scene: what is simulated, on which mesh, with which solver.

Scene(path) reads a TOML scene file; Scene.from_dict(d, base_dir=".") and
Scene.from_toml(text, base_dir=".") take the same tables. Every value is validated as the
CLI validates it: bad input raises vtb.InputError with the CLI's error line.)")
      .def(py::init([](const std::filesystem::path& file) { return read_scene(file); }), py::arg("path"))
      .def_static(
          "from_dict",
          [](const py::dict& d, const std::filesystem::path& base_dir) {
            return parse_scene(dict_to_toml(d), "<dict>",
                               base_dir.empty() ? std::filesystem::current_path() : base_dir);
          },
          py::arg("tables"), py::arg("base_dir") = std::filesystem::path(),
          "A scene from a dict of the file's tables ({'scene': {...}, 'mesh': {...}, 'fix': [{...}], ...}); "
          "paths resolve against base_dir (default: the working folder)")
      .def_static(
          "from_toml",
          [](const std::string& text, const std::filesystem::path& base_dir, const std::string& name) {
            return parse_scene(text, name, base_dir.empty() ? std::filesystem::current_path() : base_dir);
          },
          py::arg("text"), py::arg("base_dir") = std::filesystem::path(), py::arg("name") = "<string>")
      .def_static("dict_to_toml", &dict_to_toml, py::arg("tables"), "The TOML text a dict scene is read from")
      .def_property_readonly("name", [](const Scene& s) { return s.name; })
      .def_property_readonly("file", [](const Scene& s) { return s.file; })
      .def_property_readonly("duration", [](const Scene& s) { return s.duration; })
      .def_property_readonly("output_interval", [](const Scene& s) { return s.output_interval; })
      .def_property_readonly("solver", [](const Scene& s) { return s.solver.kind; })
      .def_property_readonly("filter", [](const Scene& s) { return s.solver.step.filter; })
      .def_property_readonly("springs", [](const Scene& s) { return s.solver.springs; })
      .def_property_readonly("dt", [](const Scene& s) { return s.solver.dt; })
      .def_property_readonly("young_modulus", [](const Scene& s) { return s.material.young_modulus; })
      .def_property_readonly("poisson_ratio", [](const Scene& s) { return s.material.poisson_ratio; })
      .def_property_readonly("has_haptics", [](const Scene& s) { return s.haptics.has_value(); })
      .def("__repr__", [](const Scene& s) { return "<vtb.Scene '" + s.name + "' (" + s.file.string() + ")>"; });
}

} // namespace vtb::python
