# `cmake --install build --prefix /usr/local`: the programs, the refinement and file-format
# libraries with their headers, and the wire protocol.
#
#   bin/tetrefine, bin/tetrefine_server
#   lib/libtetrefine_core.a, lib/libtetrefine_io.a
#   include/tetrefine/core/*.h, include/tetrefine/client/io/*.h   (compile with
#       -I<prefix>/include/tetrefine; the headers include each other as "core/refine.h")
#   share/tetrefine/proto/tetrefine/v1/tetrefine.proto
#
# Checked by tests/install/check_install.py (ctest InstallTree). Kept in one file so the layout
# is read in one place.
include(GNUInstallDirs)

set(TETREFINE_INSTALL_INCLUDEDIR ${CMAKE_INSTALL_INCLUDEDIR}/tetrefine)

install(TARGETS tetrefine tetrefine_server RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(TARGETS tetrefine_core tetrefine_io ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})

file(GLOB _core_headers ${PROJECT_SOURCE_DIR}/core/*.h)
install(FILES ${_core_headers} DESTINATION ${TETREFINE_INSTALL_INCLUDEDIR}/core)
file(GLOB _io_headers ${PROJECT_SOURCE_DIR}/client/io/*.h)
install(FILES ${_io_headers} DESTINATION ${TETREFINE_INSTALL_INCLUDEDIR}/client/io)

install(FILES ${PROJECT_SOURCE_DIR}/proto/tetrefine/v1/tetrefine.proto
        DESTINATION ${CMAKE_INSTALL_DATADIR}/tetrefine/proto/tetrefine/v1)
