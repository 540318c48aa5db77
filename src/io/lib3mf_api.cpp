#include "io/lib3mf_api.hpp"

#include <dlfcn.h>

namespace nonplanar::io {
namespace {

struct Loaded {
  Lib3mf api;
  std::string why;  ///< empty: loaded
};

Loaded load() {
  Loaded l;
  // RTLD_LOCAL: its symbols stay out of the program's scope (a test linked against lib3mf
  // keeps its own).
  void* lib = ::dlopen(NONPLANAR_LIB3MF_SONAME, RTLD_NOW | RTLD_LOCAL);
  if (!lib) {
    const char* e = ::dlerror();
    l.why = std::string("cannot load lib3mf (") + (e ? e : NONPLANAR_LIB3MF_SONAME) +
            "); bash scripts/setup.sh installs it";
    return l;
  }
#define NONPLANAR_LIB3MF_LOAD(name)                                                   \
  l.api.name = reinterpret_cast<decltype(l.api.name)>(::dlsym(lib, "lib3mf_" #name)); \
  if (!l.api.name && l.why.empty())                                                   \
    l.why = "lib3mf (" NONPLANAR_LIB3MF_SONAME ") lacks lib3mf_" #name ": not lib3mf 1.8?";
  NONPLANAR_LIB3MF_FUNCTIONS(NONPLANAR_LIB3MF_LOAD)
#undef NONPLANAR_LIB3MF_LOAD
  return l;  // the library stays loaded for the life of the process
}

const Loaded& loaded() {
  static const Loaded l = load();  // once, whichever thread asks first
  return l;
}

}  // namespace

const Lib3mf* load_lib3mf(std::string* why) {
  const Loaded& l = loaded();
  if (!l.why.empty()) {
    if (why) *why = l.why;
    return nullptr;
  }
  return &l.api;
}

const Lib3mf& lib3mf() {
  return loaded().api;
}

}  // namespace nonplanar::io
