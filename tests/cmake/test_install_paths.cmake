# cmake/NgiInstallPaths.cmake (ctest install_paths; cmake -P tests/cmake/test_install_paths.cmake): the paths between
# install directories that CMakeLists.txt compiles in (the models from bin/, lib/ and the Python package; the Python
# packages from bin/ for `ngi adapt`; the prefix from lib/pkgconfig), with each directory relative to the prefix or
# absolute. The old formula, file(RELATIVE_PATH ... /p/<from> /p/<to>), made /usr/lib/python3/dist-packages into
# ../usr/lib/python3/dist-packages from /usr/bin.
cmake_minimum_required(VERSION 3.25)
include(${CMAKE_CURRENT_LIST_DIR}/../../cmake/NgiInstallPaths.cmake)

set(failures 0)
function(expect prefix from to want)
  set(CMAKE_INSTALL_PREFIX "${prefix}")
  ngi_install_relative_path(got "${from}" "${to}")
  if(NOT got STREQUAL want)
    message(SEND_ERROR "prefix ${prefix}: from ${from} to ${to}: got '${got}', expected '${want}'")
    math(EXPR failures "${failures} + 1")
    set(failures ${failures} PARENT_SCOPE)
  endif()
endfunction()

# Both relative (the defaults): as before.
expect(/usr/local bin lib/python3/dist-packages ../lib/python3/dist-packages)
expect(/usr/local lib/x86_64-linux-gnu share/ngi/models ../../share/ngi/models)
expect(/usr/local lib/python3/dist-packages/ngi share/ngi/models ../../../../share/ngi/models)
expect(/usr/local lib/pkgconfig "" ../../)  # file(RELATIVE_PATH) ends an ancestor with /
expect(/usr lib/x86_64-linux-gnu/pkgconfig /usr ../../../)
# GNUInstallDirs' full paths (CMAKE_INSTALL_FULL_BINDIR) against a directory given relative or absolute.
expect(/usr /usr/bin lib/python3/dist-packages ../lib/python3/dist-packages)
expect(/usr /usr/bin /usr/lib/python3/dist-packages ../lib/python3/dist-packages)
expect(/usr /usr/lib/python3/dist-packages/ngi /usr/share/ngi/models ../../../../share/ngi/models)
expect(/opt/ngi /opt/ngi/bin /usr/lib/python3/dist-packages ../../../usr/lib/python3/dist-packages)
expect(/usr /usr/lib/x86_64-linux-gnu/pkgconfig /usr ../../../)
# An absolute libdir (Debian's -DCMAKE_INSTALL_LIBDIR=/usr/lib/x86_64-linux-gnu style) and its pkgconfig folder.
expect(/usr /usr/lib/x86_64-linux-gnu /usr/share/ngi/models ../../share/ngi/models)
expect(/usr /usr/lib/x86_64-linux-gnu/pkgconfig /usr ../../../)
# Spellings: a trailing slash, ./ and // in a directory, the same folder.
expect(/usr/ /usr/bin/ ./lib//python3/dist-packages/ ../lib/python3/dist-packages)
expect(/usr /usr/bin bin .)
expect(/ /bin lib/python3/dist-packages ../lib/python3/dist-packages)

if(failures GREATER 0)
  message(FATAL_ERROR "install_paths: ${failures} failed")
endif()
message(STATUS "install_paths: every path between install directories as expected")
