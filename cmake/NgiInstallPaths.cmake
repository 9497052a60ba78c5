# Paths between install directories, for what an installed file finds relative to its own location (the models from
# bin/, lib/ and the Python package; the Python packages from bin/ for `ngi adapt`; the prefix from lib/pkgconfig).
# A directory is relative to CMAKE_INSTALL_PREFIX (lib/python3/dist-packages) or absolute
# (-DNGI_PYTHON_INSTALL_DIR=/usr/lib/python3/dist-packages, -DCMAKE_INSTALL_LIBDIR=/usr/lib/x86_64-linux-gnu): both
# are made absolute before the path between them is taken. Tested by tests/cmake/test_install_paths.cmake (cmake -P).

# `dir` as an absolute, normalized path: as it is when absolute, else under CMAKE_INSTALL_PREFIX.
function(ngi_install_full_dir out dir)
  if(IS_ABSOLUTE "${dir}")
    set(full "${dir}")
  else()
    set(full "${CMAKE_INSTALL_PREFIX}/${dir}")
  endif()
  cmake_path(NORMAL_PATH full)
  string(REGEX REPLACE "(.)/$" "\\1" full "${full}")  # no trailing slash (/usr/ -> /usr; / stays /)
  set(${out} "${full}" PARENT_SCOPE)
endfunction()

# The relative path from install directory `from` to install directory `to` ("." when they are the same).
function(ngi_install_relative_path out from to)
  ngi_install_full_dir(from_full "${from}")
  ngi_install_full_dir(to_full "${to}")
  file(RELATIVE_PATH rel "${from_full}" "${to_full}")
  if(rel STREQUAL "")
    set(rel ".")
  endif()
  set(${out} "${rel}" PARENT_SCOPE)
endfunction()
