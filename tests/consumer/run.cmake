# Installs brdfz, moves the installed tree to another prefix, checks that its CMake files name no path
# of this machine, then builds and runs each consumer below against it:
#   cmake -DSOURCE_DIR=SRC -DBUILD_DIR=TREE -DWORK_DIR=DIR -P run.cmake
# With -DSHARED=ON -DGENERATOR=G -DVERSION=V -DSOVERSION=S (the libraries' file version and soname
# version), the libraries of SRC are first built shared in WORK_DIR, and those are installed: no
# command, tests, benchmarks or Python, and what this checks is the package, not its speed, so built
# unoptimised (clang -O0 without debug information compiles it in three quarters of -O1's time).
#
# A consumer is a folder here: a CMake project whose executable `consumer` takes a scratch folder and
# exits 0 when what it checks holds. Adding one is its folder and a consumer() line at the end.
cmake_minimum_required(VERSION 3.22)
file(REMOVE_RECURSE ${WORK_DIR})

# Runs a command; its standard output in `output`.
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed: ${ARGN}\n${out}\n${err}")
  endif()
  set(output "${out}" PARENT_SCOPE)
endfunction()

if(SHARED)
  set(BUILD_DIR ${WORK_DIR}/brdfz-shared)
  run(${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${BUILD_DIR} -G ${GENERATOR} -DBUILD_SHARED_LIBS=ON
      -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo
      "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O0 -DNDEBUG" -DBRDFZ_BUILD_CLI=OFF -DBRDFZ_BUILD_TESTS=OFF
      -DBRDFZ_BUILD_BENCH=OFF -DBRDFZ_BUILD_PYTHON=OFF)
  run(${CMAKE_COMMAND} --build ${BUILD_DIR} --parallel 2)
endif()
set(installed ${WORK_DIR}/installed)
set(prefix ${WORK_DIR}/moved)
run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${installed})
file(RENAME ${installed} ${prefix})

# Relocatable: no installed CMake file names the source or build tree, the prefix it was installed
# to, or a library of this machine by its path (third-party libraries are found by the config).
file(GLOB_RECURSE cmake_files ${prefix}/*.cmake)
if(NOT cmake_files)
  message(FATAL_ERROR "no CMake files installed in ${prefix}")
endif()
foreach(file IN LISTS cmake_files)
  file(READ ${file} text)
  foreach(path IN ITEMS ${SOURCE_DIR} ${BUILD_DIR} ${installed} /usr/lib/ /usr/include/)
    string(FIND "${text}" "${path}" at)
    if(at GREATER -1)
      message(FATAL_ERROR "${file} names ${path}")
    endif()
  endforeach()
endforeach()

# Shared libraries: versioned sonames, and the libraries find each other in the moved prefix.
if(SHARED)
  file(GLOB libraries ${prefix}/lib/libbrdfz_*.so)
  if(NOT libraries)
    message(FATAL_ERROR "no shared library installed in ${prefix}/lib")
  endif()
  foreach(so IN LISTS libraries)
    if(NOT EXISTS ${so}.${SOVERSION} OR NOT EXISTS ${so}.${VERSION})
      message(FATAL_ERROR "${so}: no versioned library (.so.${SOVERSION} -> .so.${VERSION})")
    endif()
    file(READ_ELF ${so}.${VERSION} RUNPATH runpath RPATH rpath)
    if(NOT "${runpath}${rpath}" STREQUAL "$ORIGIN")
      message(FATAL_ERROR "${so}: run path '${runpath}${rpath}', not $ORIGIN")
    endif()
  endforeach()
endif()

# consumer(NAME [FIND_WITHOUT PACKAGE...] [LINK_WITHOUT REGEX] [NEEDS_ONLY REGEX])
# Configures NAME/ against the moved prefix (with find_package of each FIND_WITHOUT package
# disabled), builds it, fails if its link command matches LINK_WITHOUT or if it loads a library other
# than brdfz's own (which must come from the moved prefix) that NEEDS_ONLY does not match, and runs it.
function(consumer name)
  cmake_parse_arguments(C "" "LINK_WITHOUT;NEEDS_ONLY" "FIND_WITHOUT" ${ARGN})
  set(dir ${WORK_DIR}/${name})
  set(disabled)
  foreach(package IN LISTS C_FIND_WITHOUT)
    list(APPEND disabled -DCMAKE_DISABLE_FIND_PACKAGE_${package}=ON)
  endforeach()
  run(${CMAKE_COMMAND} -S ${CMAKE_CURRENT_LIST_DIR}/${name} -B ${dir} -DCMAKE_PREFIX_PATH=${prefix}
      -DCMAKE_BUILD_TYPE=Release ${disabled})
  run(${CMAKE_COMMAND} --build ${dir} --verbose)
  if(C_LINK_WITHOUT)
    string(REGEX MATCH "[^\n]* -o consumer[^\n]*" link "${output}")
    if(NOT link OR link MATCHES "${C_LINK_WITHOUT}")
      message(FATAL_ERROR "${name}: link command with '${C_LINK_WITHOUT}' (or none found):\n${link}")
    endif()
  endif()
  # ldd's lines: "NAME => PATH (ADDRESS)", or "PATH (ADDRESS)" for the dynamic linker and the vDSO.
  run(ldd ${dir}/consumer)
  string(REGEX MATCHALL "[^\n]+" lines "${output}")
  foreach(line IN LISTS lines)
    if(NOT line MATCHES "^[ \t]*([^ \t]+)( => ([^ ]*))?")
      continue()
    endif()
    get_filename_component(library ${CMAKE_MATCH_1} NAME)
    set(path "${CMAKE_MATCH_3}")
    if(library MATCHES "^libbrdfz_")
      string(FIND "${path}" "${prefix}/" at)
      if(NOT at EQUAL 0)
        message(FATAL_ERROR "${name}: ${library} loaded from '${path}', not from ${prefix}")
      endif()
    elseif(C_NEEDS_ONLY AND NOT library MATCHES "${C_NEEDS_ONLY}")
      message(FATAL_ERROR "${name}: loads ${library}, beyond '${C_NEEDS_ONLY}'")
    endif()
  endforeach()
  run(${dir}/consumer ${dir})
  message("${name}: ${output}")
endfunction()

# What every C++ program loads: the C and C++ runtime (glibc's libraries, libstdc++, libgcc_s), the
# dynamic linker and the vDSO.
set(c_cxx_runtime "^(linux-vdso|ld-linux[^.]*|libc|libm|libpthread|libdl|librt|libstdc\\+\\+|libgcc_s)\\.so")

# All of brdfz (brdfz::brdfz), the fitting's kinds registered.
consumer(brdfz)
# Files but no fitting: no Ceres to find or link.
consumer(formats FIND_WITHOUT Ceres LINK_WITHOUT "ceres")
# The core: no third-party package to find, nothing beyond the C and C++ runtime to load.
consumer(core FIND_WITHOUT Ceres OpenEXR PkgConfig NEEDS_ONLY "${c_cxx_runtime}")
# The runtime alone: C++17, no third-party package, nothing beyond the C and C++ runtime to load.
consumer(runtime FIND_WITHOUT Ceres OpenEXR PkgConfig Eigen3 NEEDS_ONLY "${c_cxx_runtime}")
