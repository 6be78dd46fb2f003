#include "vtb/base/module.hh"

#include "vtb/base/atomic_file.hh"

#include <dlfcn.h>

#include <vector>

namespace vtb {
namespace {

/// ../lib/FILE from the folder of the object holding this code, then the build's path.
std::vector<std::string> candidates(const std::string& file, const std::string& build_path) {
  std::vector<std::string> paths;
  Dl_info info{};
  if (dladdr(reinterpret_cast<const void*>(&candidates), &info) && info.dli_fname) {
    std::string self = info.dli_fname;
    const auto slash = self.rfind('/');
    self = slash == std::string::npos ? "." : self.substr(0, slash);
    paths.push_back(self + "/../lib/" + file);
  }
  paths.push_back(build_path);
  return paths;
}

} // namespace

Module::Module(const std::string& file, const std::string& build_path, const std::string& what) {
  std::string tried;
  for (const std::string& path : candidates(file, build_path)) {
    m_handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
    if (m_handle) return;
    const char* why = dlerror();
    tried += (tried.empty() ? "" : "; ") + std::string(why ? why : path.c_str());
  }
  throw IoError(what + " (" + file + ") could not be loaded: " + tried);
}

Module::~Module() {
  dlclose(m_handle);
}

void* Module::symbol(const char* name) const {
  return dlsym(m_handle, name);
}

} // namespace vtb
