#pragma once
// Short number formatting for fit messages and model descriptions (private to fitting).

#include <cstdio>
#include <string>

namespace tunekit::fitting::text {

/// `v` with four significant digits, printf's %g style ("0.04512", "1.2e+04").
inline std::string g4(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

}  // namespace tunekit::fitting::text
