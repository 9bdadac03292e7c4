# Precompiled headers shared by the libraries: the standard library, fmt and nlohmann::json, which
# every library includes, parsed once for the whole build instead of once per library (with
# Eigen for the libraries at the build type's level). A precompiled header carries the
# optimisation level it was compiled at into the code that includes it (an -O2 header made the
# -O1 protocols unit take 4 s longer to compile), so there is one per level: `numeric` at the
# build type's, `not_hot` at tunekit_not_hot's -O1. A library at tunekit_inlined_O1's level (the
# simulated printer) parses its own.
#
# Only when each library is one translation unit (scripts/build, scripts/test) and only with GCC:
# a library compiled in batches precompiles its own (tunekit_precompile_headers), and the clang
# builds (sanitizers, fuzzing) parse every header themselves, so a source that forgets an
# #include still fails there. docs/benchmarks.md has what this saves.
set(TUNEKIT_SHARED_PCH OFF)
if(TUNEKIT_WHOLE_TARGET_UNITY AND CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
  set(TUNEKIT_SHARED_PCH ON)
endif()

# What most libraries include (counted over their sources), the heavy third-party headers last.
set(TUNEKIT_SHARED_PCH_HEADERS
  <algorithm> <array> <cctype> <cerrno> <charconv> <chrono> <cmath> <complex> <cstddef>
  <cstdint> <cstdio> <cstdlib> <cstring> <exception> <filesystem> <fstream> <functional>
  <iterator> <limits> <map> <memory> <numbers> <numeric> <optional> <ostream> <set> <span>
  <sstream> <stdexcept> <string> <string_view> <tuple> <type_traits> <utility> <variant>
  <vector> <fmt/format.h> <nlohmann/json.hpp>)

# tunekit_shared_pch_donor(LEVEL HEADERS...): an object library of one empty file whose product is
# the precompiled header that the libraries at LEVEL reuse.
function(tunekit_shared_pch_donor level)
  add_library(tunekit_pch_${level} OBJECT "${PROJECT_SOURCE_DIR}/cmake/shared_pch.cpp")
  set_target_properties(tunekit_pch_${level} PROPERTIES UNITY_BUILD OFF)
  target_link_libraries(tunekit_pch_${level} PRIVATE tunekit_warnings fmt::fmt nlohmann_json::nlohmann_json
                                                     Eigen3::Eigen)
  target_precompile_headers(tunekit_pch_${level} PRIVATE ${ARGN})
endfunction()

# tunekit_share_precompiled_headers(LIBRARIES...): each library reuses the header of its level.
function(tunekit_share_precompiled_headers)
  if(NOT TUNEKIT_SHARED_PCH)
    return()
  endif()
  tunekit_shared_pch_donor(numeric ${TUNEKIT_SHARED_PCH_HEADERS} <Eigen/Dense>)
  tunekit_shared_pch_donor(not_hot ${TUNEKIT_SHARED_PCH_HEADERS})
  tunekit_not_hot(tunekit_pch_not_hot)
  foreach(library IN LISTS ARGN)
    get_target_property(level ${library} TUNEKIT_OPTIMISATION)
    if(NOT level)
      target_precompile_headers(${library} REUSE_FROM tunekit_pch_numeric)
    elseif(level STREQUAL "not_hot")
      target_precompile_headers(${library} REUSE_FROM tunekit_pch_not_hot)
    endif()
  endforeach()
endfunction()
