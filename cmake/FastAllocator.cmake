# The allocator of the programs (the CLI, the server, the benchmarks): gperftools' tcmalloc
# (Debian's libgoogle-perftools-dev), which replaces malloc and new in the programs it is linked to.
#
# Why: glibc returns every freed block above its mmap threshold to the kernel, and a refinement
# frees and allocates arrays of tens of MB at every iteration (edge tables, tets, per-tet
# values); each fresh one is faulted in and zeroed by the kernel again. tcmalloc keeps freed
# spans and hands them out again. Measured 2026-11-28, 2-core VM, interleaved runs with
# LD_PRELOAD, identical output: bench/file_to_file.sh's tetrefine command (210 k -> 2.81 M tets,
# two threads) 1.66-1.97 s under glibc, 1.41-1.68 s under tcmalloc, 1.45-1.91 s under jemalloc;
# the kernel's page clearing fell from 12% of the worker's samples to 3% (perf). bench/core_bench
# BM_ToConvergence (one thread, four iterations) 2.72-3.04 s -> 2.25-2.35 s.
# What it costs: freed memory stays with the process for reuse (tcmalloc returns it to the
# kernel gradually), so a server's resident size stays near its largest call's.
#
# Off under sanitizers, which bring their own allocator, and with -DTETREFINE_TCMALLOC=OFF.
option(TETREFINE_TCMALLOC "Link the programs with tcmalloc (gperftools)" ON)
if(TETREFINE_SANITIZE OR TETREFINE_BUILD_FUZZ)
  set(TETREFINE_TCMALLOC OFF)
endif()
if(TETREFINE_TCMALLOC)
  find_package(PkgConfig REQUIRED)
  pkg_check_modules(TCMALLOC REQUIRED IMPORTED_TARGET libtcmalloc_minimal)
endif()

# Links `target` (an executable) with the allocator above, when it is on. --no-as-needed: no
# symbol of the program names tcmalloc, and a linker that drops unneeded libraries (the default
# of some distributions) would leave glibc's malloc in place without a word;
# tests/deploy/allocator_test.sh checks the programs load it.
function(tetrefine_use_fast_allocator target)
  if(TETREFINE_TCMALLOC)
    # As link options, not libraries: CMake moves a library to the end of the command, past
    # the --as-needed that other packages' flags switch on there.
    target_link_options(${target} PRIVATE
      -Wl,--push-state,--no-as-needed ${TCMALLOC_LINK_LIBRARIES} -Wl,--pop-state)
  endif()
endfunction()
