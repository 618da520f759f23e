# The fuzz targets, shared by fuzz/CMakeLists.txt (libFuzzer executables, clang only) and
# tests/hardening (the same entry points run over the corpora with any compiler, as tests).
# Target <name>: source fuzz/<name>_fuzzer.cc, corpus fuzz/corpus/<name>/.
set(TETREFINE_FUZZ_DIR ${CMAKE_CURRENT_LIST_DIR})
set(TETREFINE_FUZZ_TARGETS request response refine vtu vtk_legacy vtk_legacy_binary gmsh gmsh_binary
  medit meshb nifti nrrd metaimage vti vtk_legacy_image pvtu_index pvti_index tetgen abaqus dicom)

set(_tetrefine_fuzz_sources_request request_fuzzer.cc)
set(_tetrefine_fuzz_libs_request tetrefine_wire)
set(_tetrefine_fuzz_sources_response response_fuzzer.cc)
set(_tetrefine_fuzz_libs_response tetrefine_wire)
set(_tetrefine_fuzz_sources_refine refine_fuzzer.cc)
set(_tetrefine_fuzz_libs_refine tetrefine_core)
set(_tetrefine_fuzz_sources_pvtu_index pvtu_index_fuzzer.cc)
set(_tetrefine_fuzz_libs_pvtu_index tetrefine_io)
set(_tetrefine_fuzz_sources_pvti_index pvti_index_fuzzer.cc)
set(_tetrefine_fuzz_libs_pvti_index tetrefine_io)
set(_tetrefine_fuzz_sources_abaqus abaqus_fuzzer.cc)
set(_tetrefine_fuzz_libs_abaqus tetrefine_io)
foreach(_format vtu vtk_legacy vtk_legacy_binary gmsh gmsh_binary medit meshb tetgen)
  set(_tetrefine_fuzz_sources_${_format} ${_format}_fuzzer.cc)
  set(_tetrefine_fuzz_libs_${_format} tetrefine_fuzz_mesh_check tetrefine_io)
endforeach()
foreach(_format nifti nrrd metaimage vti vtk_legacy_image dicom)
  set(_tetrefine_fuzz_sources_${_format} ${_format}_fuzzer.cc)
  set(_tetrefine_fuzz_libs_${_format} tetrefine_fuzz_volume_check tetrefine_io)
endforeach()

# The helpers every target shares, compiled once rather than once per executable (13 times
# fuzz_support.cc and replay_main.cc, 7 times the mesh check): a third fewer compiles in each
# build that has the fuzz targets or their corpus replay tests. Created on first use, as both
# fuzz/ and tests/hardening/ call tetrefine_add_fuzz_executable.
function(_tetrefine_fuzz_helpers)
  if(TARGET tetrefine_fuzz_support)
    return()
  endif()
  add_library(tetrefine_fuzz_support STATIC ${TETREFINE_FUZZ_DIR}/fuzz_support.cc)
  target_link_libraries(tetrefine_fuzz_support PUBLIC tetrefine_core)
  add_library(tetrefine_fuzz_mesh_check STATIC ${TETREFINE_FUZZ_DIR}/mesh_parser_check.cc)
  target_link_libraries(tetrefine_fuzz_mesh_check PUBLIC tetrefine_fuzz_support tetrefine_io)
  add_library(tetrefine_fuzz_volume_check STATIC ${TETREFINE_FUZZ_DIR}/volume_reader_check.cc)
  target_link_libraries(tetrefine_fuzz_volume_check PUBLIC tetrefine_fuzz_support tetrefine_io)
endfunction()

# tetrefine_add_fuzz_executable(<executable> <target> [main library]): the target's entry point
# and helpers; the caller adds a main (libFuzzer's by -fsanitize=fuzzer, or the corpus replay
# library tetrefine_fuzz_replay_main).
function(tetrefine_add_fuzz_executable executable target)
  _tetrefine_fuzz_helpers()
  set(sources ${_tetrefine_fuzz_sources_${target}})
  list(TRANSFORM sources PREPEND ${TETREFINE_FUZZ_DIR}/)
  add_executable(${executable} ${sources})
  target_link_libraries(${executable} PRIVATE ${ARGN} ${_tetrefine_fuzz_libs_${target}}
    tetrefine_fuzz_support)
endfunction()
