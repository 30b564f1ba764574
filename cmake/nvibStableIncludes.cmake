# nvib_stable_includes(<imported target>...): build-tree copies of the headers
# of imported targets, so that a cached build folder survives a moved build
# environment.
#
# pip builds each wheel in a fresh isolated environment at a random /tmp path,
# so the include folders of the pip-provided Eigen and pybind11 move from one
# `pip install .` to the next. A compile command naming them would change, the
# headers recorded as its dependencies would be gone, and the whole module
# would be compiled again although nothing in it changed. This function copies
# each include folder of the given targets into <build>/stable-include/,
# writing only the files whose content differs (unchanged files keep their
# timestamps), and points the targets at the copies. A new Eigen or pybind11
# release changes the copied files and so still triggers a rebuild.
#
# Needs CMake >= 3.21 (file(COPY_FILE ... ONLY_IF_DIFFERENT)); with an older
# CMake the targets are left as they are (the build is correct, only not
# reused across isolated environments).
function(nvib_stable_includes)
  if(CMAKE_VERSION VERSION_LESS 3.21)
    return()
  endif()
  foreach(target IN LISTS ARGN)
    if(NOT TARGET ${target})
      continue()
    endif()
    get_target_property(aliased ${target} ALIASED_TARGET)
    if(aliased)
      set(target ${aliased})
    endif()
    get_target_property(dirs ${target} INTERFACE_INCLUDE_DIRECTORIES)
    if(NOT dirs)
      continue()
    endif()
    string(MAKE_C_IDENTIFIER "${target}" name)
    set(copies "")
    set(index 0)
    foreach(dir IN LISTS dirs)
      if(dir MATCHES "\\$<" OR NOT IS_DIRECTORY "${dir}")
        list(APPEND copies "${dir}")  # a generator expression or a missing folder: kept as it is
        continue()
      endif()
      set(dest "${CMAKE_BINARY_DIR}/stable-include/${name}/${index}")
      math(EXPR index "${index} + 1")
      file(GLOB_RECURSE files RELATIVE "${dir}" LIST_DIRECTORIES false "${dir}/*")
      set(made "")
      foreach(file IN LISTS files)
        get_filename_component(sub "${dest}/${file}" DIRECTORY)
        if(NOT sub IN_LIST made)
          file(MAKE_DIRECTORY "${sub}")
          list(APPEND made "${sub}")
        endif()
        file(COPY_FILE "${dir}/${file}" "${dest}/${file}" ONLY_IF_DIFFERENT)
      endforeach()
      list(APPEND copies "${dest}")
    endforeach()
    set_target_properties(${target} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${copies}")
  endforeach()
endfunction()
