# ctest driver for the installed-package test (run with cmake -P):
#   install the built project into a fresh prefix, configure and build tests/consumer against
#   it, run the shared and static consumers, then compile the same main.cc with pkg-config;
#   import the installed Python module.
# Inputs: -DBUILD_DIR=<nonbloppy build> -DSOURCE_DIR=<nonbloppy source> -DWORK_DIR=<scratch>
#         -DCXX=<compiler> -DBUILD_TYPE=<Release|...> and the project's -DCXX_FLAGS and
#         -DEXE_LINKER_FLAGS (e.g. sanitizers: the consumer must be built the same way), and
#         -DPYTHON=<interpreter> where the build made the Python module (empty: none)
cmake_minimum_required(VERSION 3.18)

function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    string(REPLACE ";" " " cmd "${ARGN}")
    message(FATAL_ERROR "failed (${rc}): ${cmd}")
  endif()
endfunction()

file(REMOVE_RECURSE "${WORK_DIR}")
set(prefix "${WORK_DIR}/prefix")
run(${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${prefix}")
foreach(f include/nonbloppy/BuildSurface.h include/nonbloppy/Export.h bin/nonbloppy)
  if(NOT EXISTS "${prefix}/${f}")
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()

run(${CMAKE_COMMAND} -S "${SOURCE_DIR}/tests/consumer" -B "${WORK_DIR}/build"
    -DCMAKE_BUILD_TYPE=${BUILD_TYPE} -DCMAKE_CXX_COMPILER=${CXX}
    -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_FIND_PACKAGE_NO_PACKAGE_REGISTRY=ON
    "-DCMAKE_CXX_FLAGS=${CXX_FLAGS}" "-DCMAKE_EXE_LINKER_FLAGS=${EXE_LINKER_FLAGS}")
run(${CMAKE_COMMAND} --build "${WORK_DIR}/build" -j1)
run("${WORK_DIR}/build/consumer_shared")
run("${WORK_DIR}/build/consumer_static")

# The same program built without CMake, from the pkg-config file alone.
file(GLOB pcdir LIST_DIRECTORIES true "${prefix}/lib*/pkgconfig" "${prefix}/lib/*/pkgconfig")
set(ENV{PKG_CONFIG_PATH} "${pcdir}")
execute_process(COMMAND pkg-config --cflags --libs nonbloppy
                OUTPUT_VARIABLE flags OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE rc)
execute_process(COMMAND pkg-config --variable=libdir nonbloppy
                OUTPUT_VARIABLE libdir OUTPUT_STRIP_TRAILING_WHITESPACE)
if(NOT rc EQUAL 0 OR flags STREQUAL "")
  message(FATAL_ERROR "pkg-config found no nonbloppy in ${pcdir}")
endif()
message(STATUS "pkg-config flags: ${flags}")
separate_arguments(flags UNIX_COMMAND "${flags}")
separate_arguments(extra UNIX_COMMAND "${CXX_FLAGS} ${EXE_LINKER_FLAGS}")
run(${CXX} -O1 ${extra} "${SOURCE_DIR}/tests/consumer/main.cc" -o "${WORK_DIR}/consumer_pkgconfig"
    ${flags} "-Wl,-rpath,${libdir}")
run("${WORK_DIR}/consumer_pkgconfig")

# The Python module, where the build made one: it imports from where it was installed and
# meshes (as the suite's python_module test does from the build tree).
if(PYTHON)
  file(GLOB_RECURSE module "${prefix}/*/nonbloppy.cpython-*.so")
  if(NOT module)
    message(FATAL_ERROR "not installed: the Python module")
  endif()
  get_filename_component(moduledir "${module}" DIRECTORY)
  set(ENV{PYTHONPATH} "${moduledir}")
  # Statements on lines of their own: CMake would split the argument at a ';'.
  run(${PYTHON} -c "import nonbloppy
mesh = nonbloppy.build_surface([[0, 0, 0]], radius=1.0, threshold=1.0, voxel_size=0.1, method='paper', iterations=0)
assert nonbloppy.__file__.startswith('${prefix}/'), nonbloppy.__file__
assert len(mesh.vertices) > 100, mesh")
endif()
