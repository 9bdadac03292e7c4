#include "tunekit/core/shared_library.hpp"

#include <dlfcn.h>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"

namespace tunekit::core {

SharedLibrary::SharedLibrary(std::string soname, std::string purpose, std::string package)
    : soname_(std::move(soname)), purpose_(std::move(purpose)), package_(std::move(package)) {}

void* SharedLibrary::symbol(const char* name) {
  std::call_once(opened_, [this] {
    // RTLD_GLOBAL: the library may load plug-ins of its own (PLplot's output drivers) that
    // expect its symbols to be visible.
    handle_ = dlopen(soname_.c_str(), RTLD_NOW | RTLD_GLOBAL);
    if (handle_ == nullptr) {
      const char* why = dlerror();
      open_error_ = why != nullptr ? why : "unknown reason";
    }
  });
  if (handle_ == nullptr)
    throw Error(ExitCode::fit_failed, fmt::format("{} need {}, which could not be loaded ({}); install the Debian "
                                                  "package {}",
                                                  purpose_, soname_, open_error_, package_));
  dlerror();
  void* p = dlsym(handle_, name);
  if (p == nullptr)
    throw Error(ExitCode::fit_failed,
                fmt::format("{} need {} with the function {}, which this version lacks; install the Debian package {}",
                            purpose_, soname_, name, package_));
  return p;
}

}  // namespace tunekit::core
