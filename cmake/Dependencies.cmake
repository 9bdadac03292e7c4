# Every third-party dependency comes from a Debian 12 package (scripts/install-deps).
# When one is missing, configuration stops and names the package to install.

find_package(PkgConfig QUIET)

macro(tunekit_missing what debian_package)
  message(FATAL_ERROR
    "tunekit: ${what} not found. Install the Debian package '${debian_package}' "
    "(or run scripts/install-deps as root).")
endmacro()

find_package(Eigen3 3.3 QUIET NO_MODULE)
if(NOT Eigen3_FOUND)
  tunekit_missing("Eigen3" "libeigen3-dev")
endif()

find_package(Ceres QUIET)
if(NOT Ceres_FOUND)
  tunekit_missing("Ceres Solver" "libceres-dev")
endif()

# The matrix pencil's singular values and eigenvalues (fitting/src/damped_sinusoids.cpp): LAPACK's
# Fortran interface, which Ceres links too.
find_package(LAPACK QUIET)
if(NOT LAPACK_FOUND)
  tunekit_missing("LAPACK" "liblapack-dev")
endif()

# Debian ships the C and the C++ NLopt configs under the same package name; ask for the C++ one.
find_package(NLopt QUIET CONFIG
  HINTS "/usr/lib/${CMAKE_LIBRARY_ARCHITECTURE}/cmake/nlopt_cxx" "/usr/lib/cmake/nlopt_cxx")
if(NOT NLopt_FOUND OR NOT TARGET NLopt::nlopt_cxx)
  tunekit_missing("NLopt (C++ interface)" "libnlopt-cxx-dev")
endif()

# Not imgcodecs: it drags ~140 shared libraries (GDAL, poppler, HDF5, ...) into every process
# and costs ~0.1 s of dynamic loading at each start. Image files go through stb (below).
find_package(OpenCV QUIET COMPONENTS core imgproc calib3d)
if(NOT OpenCV_FOUND)
  tunekit_missing("OpenCV" "libopencv-dev")
endif()
# ChArUco scale targets when the contrib aruco module is installed (libopencv-contrib-dev).
find_package(OpenCV QUIET OPTIONAL_COMPONENTS aruco)
set(TUNEKIT_HAVE_ARUCO OFF)
if(OpenCV_aruco_FOUND)
  set(TUNEKIT_HAVE_ARUCO ON)
else()
  message(STATUS "OpenCV aruco module not found (libopencv-contrib-dev): ChArUco boards are not accepted")
endif()

find_package(nlohmann_json 3.10 QUIET)
if(NOT nlohmann_json_FOUND)
  tunekit_missing("nlohmann::json" "nlohmann-json3-dev")
endif()

find_package(CLI11 QUIET CONFIG)
if(NOT CLI11_FOUND)
  find_path(CLI11_INCLUDE_DIR CLI/CLI.hpp)
  if(NOT CLI11_INCLUDE_DIR)
    tunekit_missing("CLI11" "libcli11-dev")
  endif()
  add_library(CLI11::CLI11 INTERFACE IMPORTED)
  target_include_directories(CLI11::CLI11 INTERFACE "${CLI11_INCLUDE_DIR}")
endif()

find_package(fmt QUIET)
if(NOT fmt_FOUND)
  tunekit_missing("fmt" "libfmt-dev")
endif()

find_package(tomlplusplus QUIET)
if(NOT tomlplusplus_FOUND)
  tunekit_missing("toml++" "libtomlplusplus-dev")
endif()

find_package(Boost 1.74 QUIET)
if(NOT Boost_FOUND)
  tunekit_missing("Boost (header-only Boost.Math)" "libboost-dev")
endif()

find_package(OpenSSL QUIET COMPONENTS Crypto)
if(NOT OpenSSL_FOUND)
  tunekit_missing("OpenSSL libcrypto (SHA-256 of inputs)" "libssl-dev")
endif()

find_package(Threads REQUIRED)

if(NOT PkgConfig_FOUND)
  tunekit_missing("pkg-config" "pkg-config")
endif()
pkg_check_modules(FFTW3 QUIET IMPORTED_TARGET fftw3)
if(NOT FFTW3_FOUND)
  tunekit_missing("FFTW3" "libfftw3-dev")
endif()
pkg_check_modules(SERIALPORT QUIET IMPORTED_TARGET libserialport)
if(NOT SERIALPORT_FOUND)
  tunekit_missing("libserialport" "libserialport-dev")
endif()
pkg_check_modules(PLPLOT QUIET IMPORTED_TARGET plplot-c++)
if(NOT PLPLOT_FOUND)
  tunekit_missing("PLplot (C++ binding)" "libplplot-dev")
endif()
# stb_image / stb_image_write: reading photos and writing PNGs (ident/image_io).
pkg_check_modules(STB QUIET IMPORTED_TARGET stb)
if(NOT STB_FOUND)
  tunekit_missing("stb_image (image files)" "libstb-dev")
endif()

# Zstandard: reading Shake&Tune's .stdata measurement files (ident/shaketune_stdata).
pkg_check_modules(ZSTD QUIET IMPORTED_TARGET libzstd)
if(NOT ZSTD_FOUND)
  tunekit_missing("Zstandard (Shake&Tune .stdata files)" "libzstd-dev")
endif()

# The calibration history: SQLite (the embedded default) and libpq (a farm's PostgreSQL server).
pkg_check_modules(SQLITE3 QUIET IMPORTED_TARGET sqlite3)
if(NOT SQLITE3_FOUND)
  tunekit_missing("SQLite 3 (calibration history)" "libsqlite3-dev")
endif()
pkg_check_modules(LIBPQ QUIET IMPORTED_TARGET libpq)
if(NOT LIBPQ_FOUND)
  tunekit_missing("libpq (PostgreSQL client, calibration history)" "libpq-dev")
endif()

# tunekit_soname(<var> <pkg-config prefix> <library name>): the SONAME ("libpq.so.5") of a library
# pkg-config found. PLplot and libpq are opened with dlopen when a command first needs them
# (core/shared_library.hpp), not linked: each brings a dozen or more libraries of its own that
# every other command would load, map and relocate at start-up.
function(tunekit_soname var prefix name)
  find_library(_tunekit_lib NAMES ${name} HINTS ${${prefix}_LIBRARY_DIRS} NO_CACHE)
  if(NOT _tunekit_lib OR NOT CMAKE_OBJDUMP)
    message(FATAL_ERROR "tunekit: cannot find lib${name} (or objdump) to read its SONAME")
  endif()
  execute_process(COMMAND "${CMAKE_OBJDUMP}" -p "${_tunekit_lib}" OUTPUT_VARIABLE _tunekit_dump
                  RESULT_VARIABLE _tunekit_rc)
  if(NOT _tunekit_rc EQUAL 0 OR NOT _tunekit_dump MATCHES "SONAME +([^ \n]+)")
    message(FATAL_ERROR "tunekit: cannot read the SONAME of ${_tunekit_lib}")
  endif()
  set(${var} "${CMAKE_MATCH_1}" PARENT_SCOPE)
endfunction()
tunekit_soname(TUNEKIT_PLPLOT_SONAME PLPLOT plplot)
tunekit_soname(TUNEKIT_LIBPQ_SONAME LIBPQ pq)
# tunekit_headers_only(TARGET DIRS...): a library's headers, for the build only (nothing to link,
# nothing in the installed package).
function(tunekit_headers_only target)
  add_library(${target} INTERFACE)
  target_include_directories(${target} SYSTEM INTERFACE ${ARGN})
endfunction()
tunekit_headers_only(tunekit_plplot_headers ${PLPLOT_INCLUDE_DIRS})
tunekit_headers_only(tunekit_libpq_headers ${LIBPQ_INCLUDE_DIRS})
# libcrypto (SHA-256, Base64) and SQLite are opened on first use too: both are bound at load
# time in full (BIND_NOW), some 5,000 symbol lookups at every start of every command.
tunekit_soname(TUNEKIT_LIBCRYPTO_SONAME OPENSSL crypto)
tunekit_soname(TUNEKIT_SQLITE3_SONAME SQLITE3 sqlite3)
tunekit_headers_only(tunekit_openssl_headers ${OPENSSL_INCLUDE_DIR})
tunekit_headers_only(tunekit_sqlite3_headers ${SQLITE3_INCLUDE_DIRS})

if(TUNEKIT_BUILD_TESTS)
  find_package(Catch2 2 QUIET)
  if(NOT Catch2_FOUND)
    tunekit_missing("Catch2" "catch2")
  endif()
endif()
