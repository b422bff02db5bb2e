# The scene loader and everything it calls: the COLLADA reader, the scene builder and their
# support code, relative to the repository root. The main build compiles them into candela_core
# (CMakeLists.txt); the libFuzzer build (tools/fuzz/CMakeLists.txt) compiles the same list with
# the sanitizers. One list, so a file the loader comes to need is never missing from either.
# Nothing here may need Embree or OpenImageIO: the fuzz build links neither.
set(CANDELA_LOADER_SOURCES
  src/io/collada.cpp
  src/io/collada_context.cpp
  src/io/collada_mesh.cpp
  src/math/mat4.cpp
  src/sampling/unit_cdf.cpp
  src/scene/builder.cpp
  src/scene/scene.cpp
  src/scene/scene_editor.cpp
  src/util/enum_table.cpp
  src/util/error.cpp
  src/util/log.cpp
  src/util/process_clock.cpp
  src/util/strings.cpp)
