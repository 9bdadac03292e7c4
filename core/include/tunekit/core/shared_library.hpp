#pragma once
// A system shared library opened on first use (dlopen) instead of at start-up. Libraries that
// only a few commands need (PLplot for figures, libpq for a PostgreSQL history) and that bring
// dozens of libraries of their own are reached through this, so that every other command starts
// without loading, mapping and relocating them.

#include <mutex>
#include <string>

namespace tunekit::core {

class SharedLibrary {
 public:
  /// `soname`: the file name the dynamic loader looks up ("libpq.so.5"); `purpose`: what it is
  /// needed for, and `package`: the Debian package that installs it, both for the error message.
  SharedLibrary(std::string soname, std::string purpose, std::string package);
  SharedLibrary(const SharedLibrary&) = delete;
  SharedLibrary& operator=(const SharedLibrary&) = delete;

  /// The address of `name` in the library, opening it on the first call (thread-safe). Throws
  /// Error with exit code 1 (a requirement unmet) naming the library, its purpose and package
  /// when it cannot be opened or lacks the symbol. The library stays loaded until exit.
  void* symbol(const char* name);

  /// symbol() as a function pointer of the type of `F` (use decltype(&c_function)).
  template <class F>
  F function(const char* name) {
    return reinterpret_cast<F>(symbol(name));
  }

 private:
  std::string soname_, purpose_, package_;
  std::once_flag opened_;
  void* handle_ = nullptr;
  std::string open_error_;
};

}  // namespace tunekit::core
