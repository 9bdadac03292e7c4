// Start-up: the tunekit executable does not load the libraries only a few commands need. PLplot
// (figures) and libpq (a PostgreSQL history) bring a dozen or more libraries each; they are
// opened on first use, so `tunekit --version` or `tunekit shaper` never map or relocate them.
#include <catch2/catch.hpp>

#include <cstdio>
#include <string>

#include <fmt/format.h>

namespace {

// The shared libraries the dynamic loader maps for the tunekit executable (as ldd lists them).
std::string loaded_libraries() {
  const std::string cmd = fmt::format("LD_TRACE_LOADED_OBJECTS=1 '{}' 2>&1", TUNEKIT_EXE);
  std::string out;
  FILE* p = popen(cmd.c_str(), "r");
  REQUIRE(p != nullptr);
  char buf[4096];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
  pclose(p);
  return out;
}

}  // namespace

TEST_CASE("the tunekit executable loads neither PLplot nor libpq at start-up") {
  const std::string libs = loaded_libraries();
  INFO(libs);
  REQUIRE(libs.find("libc.so") != std::string::npos);  // the listing worked
  CHECK(libs.find("libplplot") == std::string::npos);
  CHECK(libs.find("libpq.so") == std::string::npos);
  CHECK(libs.find("libgssapi") == std::string::npos);  // one of libpq's own dependencies
}
