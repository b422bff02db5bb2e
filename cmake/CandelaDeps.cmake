# Finds candela's system dependencies (Debian bookworm packages). A missing package stops the
# configure step with the name of the Debian package that provides it.

macro(candela_require found_var what debian_pkg)
  if(NOT ${found_var})
    message(FATAL_ERROR "candela needs ${what}: install it with `apt-get install ${debian_pkg}`")
  endif()
endmacro()

find_package(embree 3 QUIET)
candela_require(embree_FOUND "Embree 3" "libembree-dev")

find_package(TBB QUIET)
candela_require(TBB_FOUND "oneTBB" "libtbb-dev")

find_package(tinyxml2 QUIET)
candela_require(tinyxml2_FOUND "tinyxml2" "libtinyxml2-dev")

find_package(CLI11 QUIET)
candela_require(CLI11_FOUND "CLI11" "libcli11-dev")

find_package(fmt CONFIG QUIET)
candela_require(fmt_FOUND "{fmt}" "libfmt-dev")

find_package(nlohmann_json 3 CONFIG QUIET)
candela_require(nlohmann_json_FOUND "nlohmann/json" "nlohmann-json3-dev")

# Images are written and read through OpenImageIO (in the image module); OpenEXR is used
# directly for one thing OpenImageIO lacks, reading an EXR's pixels without loading OpenImageIO's
# dependency tree (the environment map a render needs before its first pass: io/exr_pixels.h).
# OpenEXR's config loads Imath's, whose target file (Debian bookworm) names the Python binding
# PyImath, a separate package candela does not use, and reports its absence in a 9-line status
# block; status messages are held back while it loads (a missing OpenEXR still stops the
# configure below).
set(_candela_log_level "${CMAKE_MESSAGE_LOG_LEVEL}")
set(CMAKE_MESSAGE_LOG_LEVEL NOTICE)
find_package(OpenEXR 3 CONFIG QUIET)
set(CMAKE_MESSAGE_LOG_LEVEL "${_candela_log_level}")
unset(_candela_log_level)
candela_require(OpenEXR_FOUND "OpenEXR" "libopenexr-dev")

# OpenImageIO's own CMake config on bookworm names /usr/include/opencv4 as an include directory
# and fails unless OpenCV's development files are installed; its pkg-config file is correct.
find_package(PkgConfig QUIET)
candela_require(PKG_CONFIG_FOUND "pkg-config" "pkg-config")
pkg_check_modules(OIIO QUIET IMPORTED_TARGET OpenImageIO)
candela_require(OIIO_FOUND "OpenImageIO" "libopenimageio-dev")

if(CANDELA_BUILD_TESTS)
  find_package(Catch2 2 QUIET)
  candela_require(Catch2_FOUND "Catch2 v2" "catch2")
endif()
