# The fuzz targets, shared by fuzz/CMakeLists.txt (libFuzzer executables, clang only) and
# tests/hardening (the same entry points run over the corpora with any compiler, as tests).
# Target <name>: source fuzz/<name>_fuzzer.cc, corpus fuzz/corpus/<name>/.
set(TETREFINE_FUZZ_DIR ${CMAKE_CURRENT_LIST_DIR})
set(TETREFINE_FUZZ_TARGETS request response refine vtu vtk_legacy vtk_legacy_binary gmsh gmsh_binary
  medit meshb nifti nrrd metaimage)

set(_tetrefine_fuzz_sources_request request_fuzzer.cc)
set(_tetrefine_fuzz_libs_request tetrefine_wire)
set(_tetrefine_fuzz_sources_response response_fuzzer.cc)
set(_tetrefine_fuzz_libs_response tetrefine_wire)
set(_tetrefine_fuzz_sources_refine refine_fuzzer.cc)
set(_tetrefine_fuzz_libs_refine tetrefine_core)
foreach(_format vtu vtk_legacy vtk_legacy_binary gmsh gmsh_binary medit meshb)
  set(_tetrefine_fuzz_sources_${_format} ${_format}_fuzzer.cc mesh_parser_check.cc)
  set(_tetrefine_fuzz_libs_${_format} tetrefine_io)
endforeach()
foreach(_format nifti nrrd metaimage)
  set(_tetrefine_fuzz_sources_${_format} ${_format}_fuzzer.cc volume_reader_check.cc)
  set(_tetrefine_fuzz_libs_${_format} tetrefine_io)
endforeach()

# tetrefine_add_fuzz_executable(<executable> <target> [extra sources...]): the target's entry
# point and helpers; the caller adds a main (libFuzzer's, or fuzz/replay_main.cc).
function(tetrefine_add_fuzz_executable executable target)
  set(sources fuzz_support.cc ${_tetrefine_fuzz_sources_${target}})
  list(TRANSFORM sources PREPEND ${TETREFINE_FUZZ_DIR}/)
  add_executable(${executable} ${sources} ${ARGN})
  target_link_libraries(${executable} PRIVATE ${_tetrefine_fuzz_libs_${target}})
endfunction()
