# Install rules and the CMake package another project finds with `find_package(tunekit)`:
#
#   find_package(tunekit 0.1 REQUIRED)
#   target_link_libraries(my_program PRIVATE tunekit::fitting)   # or tunekit::ident, ...
#
# Installed: the static libraries, their public headers (include/tunekit/<library>/) and
# lib/cmake/tunekit/{tunekitConfig,tunekitConfigVersion,tunekitTargets}.cmake. The exported
# targets carry their include directory and their dependencies; tunekitConfig.cmake finds those
# dependencies again (the same Debian packages as cmake/Dependencies.cmake). docs/cpp-api.md
# and examples/ show the use.

include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(TUNEKIT_INSTALL_CMAKEDIR "${CMAKE_INSTALL_LIBDIR}/cmake/tunekit")
# The OpenCV modules the exported libraries link (cmake/Dependencies.cmake).
set(TUNEKIT_OPENCV_COMPONENTS "core imgproc calib3d")
if(TUNEKIT_HAVE_ARUCO)
  string(APPEND TUNEKIT_OPENCV_COMPONENTS " aruco")
endif()

# tunekit_install_library(TARGET NAME): installs library TARGET as tunekit::NAME with the headers
# of its include/ folder. The libraries declare their include folder and the project's warning
# flags for the build tree only; this makes both build-only in what is exported:
#  - an include directory inside the source or build tree (a generated header) becomes
#    $<BUILD_INTERFACE:...>, its headers are installed, and the installed headers' folder
#    $<INSTALL_INTERFACE:include> takes its place;
#  - tunekit_warnings (compile flags of this project, nothing to link) leaves the link interface
#    (a static library passes its private dependencies on as $<LINK_ONLY:...>).
function(tunekit_install_library target name)
  if(NOT TARGET ${target})
    return()
  endif()
  add_library(tunekit::${name} ALIAS ${target})
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${name})

  get_target_property(dirs ${target} INTERFACE_INCLUDE_DIRECTORIES)
  if(NOT dirs)
    set(dirs "")
  endif()
  set(fixed_dirs "")
  foreach(dir IN LISTS dirs)
    set(in_source_tree OFF)
    set(in_build_tree OFF)
    if(NOT dir MATCHES "^\\$<")
      cmake_path(IS_PREFIX PROJECT_SOURCE_DIR "${dir}" NORMALIZE in_source_tree)
      cmake_path(IS_PREFIX PROJECT_BINARY_DIR "${dir}" NORMALIZE in_build_tree)
    endif()
    if(NOT in_source_tree AND NOT in_build_tree)
      list(APPEND fixed_dirs "${dir}")
    else()
      if(EXISTS "${dir}")
        install(DIRECTORY "${dir}/" DESTINATION "${CMAKE_INSTALL_INCLUDEDIR}"
                FILES_MATCHING PATTERN "*.hpp" PATTERN "*.h")
      endif()
      list(APPEND fixed_dirs "$<BUILD_INTERFACE:${dir}>")
    endif()
  endforeach()
  list(APPEND fixed_dirs "$<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>")
  set_target_properties(${target} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${fixed_dirs}")

  get_target_property(links ${target} INTERFACE_LINK_LIBRARIES)
  if(links)
    list(REMOVE_ITEM links tunekit_warnings "$<LINK_ONLY:tunekit_warnings>")
    set_target_properties(${target} PROPERTIES INTERFACE_LINK_LIBRARIES "${links}")
  endif()

  install(TARGETS ${target} EXPORT tunekitTargets
          ARCHIVE DESTINATION "${CMAKE_INSTALL_LIBDIR}"
          LIBRARY DESTINATION "${CMAKE_INSTALL_LIBDIR}")
endfunction()

# One line per library, lowest layer first (scripts/check-layers holds the layer table). A
# library that does not exist (yet) is skipped; every library an installed one links must be here.
tunekit_install_library(tunekit_core core)
tunekit_install_library(tunekit_fitting fitting)
tunekit_install_library(tunekit_formats formats)
tunekit_install_library(tunekit_ident ident)
tunekit_install_library(tunekit_design design)
tunekit_install_library(tunekit_vision vision)
tunekit_install_library(tunekit_firmware firmware)
tunekit_install_library(tunekit_machine machine)
tunekit_install_library(tunekit_sim sim)
tunekit_install_library(tunekit_protocols protocols)
tunekit_install_library(tunekit_history history)
foreach(room results presentation analyses commands guided)
  tunekit_install_library(tunekit_calibration_${room} calibration_${room})
endforeach()
tunekit_install_library(tunekit_calibration calibration)

install(EXPORT tunekitTargets NAMESPACE tunekit:: DESTINATION "${TUNEKIT_INSTALL_CMAKEDIR}")

configure_package_config_file("${CMAKE_CURRENT_LIST_DIR}/tunekitConfig.cmake.in"
  "${PROJECT_BINARY_DIR}/tunekitConfig.cmake" INSTALL_DESTINATION "${TUNEKIT_INSTALL_CMAKEDIR}")
# 0.x: a minor version may change the API, so only the same minor version is compatible.
write_basic_package_version_file("${PROJECT_BINARY_DIR}/tunekitConfigVersion.cmake"
  VERSION "${PROJECT_VERSION}" COMPATIBILITY SameMinorVersion)
install(FILES "${PROJECT_BINARY_DIR}/tunekitConfig.cmake" "${PROJECT_BINARY_DIR}/tunekitConfigVersion.cmake"
        DESTINATION "${TUNEKIT_INSTALL_CMAKEDIR}")
