# Install rules (`cmake --install BUILD --prefix P`, which `./irdist install --prefix P` runs):
#   P/bin/irdist                    the program (finds P/share/irdist from its own real path)
#   P/share/irdist/recipes/         the shipped recipes and rig files (recipes/rigs/)
#   P/share/doc/irdist/             README.md and docs/
#   P/<python dir>/irdist/          the Python module (IRDIST_PYTHON_INSTALL_DIR below)
# The virtual camera's GenICam XML is compiled into the program (sim/virtual_camera_xml.cc.in).
# Nothing is written through a symbolic link: the folders are checked first
# (cmake/IrdistInstallCheck.cmake), before the first file is installed.
include(GNUInstallDirs)

set(_irdist_check_links "include(${PROJECT_SOURCE_DIR}/cmake/IrdistInstallCheck.cmake)
  irdist_refuse_links(\"\$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}\"")
install(CODE "${_irdist_check_links} ${CMAKE_INSTALL_BINDIR}/irdist
  ${CMAKE_INSTALL_DATADIR}/irdist ${CMAKE_INSTALL_DOCDIR})")
install(TARGETS irdist RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/recipes/ DESTINATION ${CMAKE_INSTALL_DATADIR}/irdist/recipes)
install(FILES ${PROJECT_SOURCE_DIR}/README.md DESTINATION ${CMAKE_INSTALL_DOCDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs/ DESTINATION ${CMAKE_INSTALL_DOCDIR})

if(TARGET irdist_python)
  # Where P's Python finds modules: Debian's layout lib/python3/dist-packages when the interpreter
  # is Debian's (its sys.path has /usr/lib/python3/dist-packages), else its site-packages.
  execute_process(COMMAND ${Python3_EXECUTABLE} -c [=[
import os, sys, sysconfig
if any(p.rstrip("/").endswith("lib/python3/dist-packages") for p in sys.path):
    print("lib/python3/dist-packages")
else:
    base = "/prefix"
    path = sysconfig.get_path("platlib", "posix_prefix", vars={"base": base, "platbase": base})
    print(os.path.relpath(path, base))
]=] OUTPUT_VARIABLE _irdist_python_dir OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE _irdist_rc)
  if(NOT _irdist_rc EQUAL 0 OR _irdist_python_dir STREQUAL "")
    set(_irdist_python_dir lib/python3/dist-packages)
  endif()
  set(IRDIST_PYTHON_INSTALL_DIR ${_irdist_python_dir} CACHE STRING
    "Where, under the install prefix, the Python module irdist goes")
  install(CODE "${_irdist_check_links} ${IRDIST_PYTHON_INSTALL_DIR}/irdist)")
  install(TARGETS irdist_python LIBRARY DESTINATION ${IRDIST_PYTHON_INSTALL_DIR}/irdist)
  install(FILES ${PROJECT_SOURCE_DIR}/python/irdist/__init__.py
    DESTINATION ${IRDIST_PYTHON_INSTALL_DIR}/irdist)
  # The installed module runs P/bin/irdist: its path relative to the package, so the prefix can
  # be moved.
  file(RELATIVE_PATH _irdist_bin_from_package
    /prefix/${IRDIST_PYTHON_INSTALL_DIR}/irdist /prefix/${CMAKE_INSTALL_BINDIR}/irdist)
  file(WRITE ${PROJECT_BINARY_DIR}/python/install/_location.py
    "# Written by cmake/IrdistInstall.cmake: P/bin/irdist, relative to this package.\n"
    "import os\n"
    "EXECUTABLE = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)),\n"
    "                                           \"${_irdist_bin_from_package}\"))\n")
  install(FILES ${PROJECT_BINARY_DIR}/python/install/_location.py
    DESTINATION ${IRDIST_PYTHON_INSTALL_DIR}/irdist)
endif()
