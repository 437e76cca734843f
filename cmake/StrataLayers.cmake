# One CMake library per source folder, in the order cmake/layers.txt declares (read here and by
# scripts/check_layers.sh, so the build and the check cannot disagree).
#
# Enforcement: every layer is compiled against a view of the source tree that holds only the folders it may
# include: ${CMAKE_BINARY_DIR}/layers/<folder>-<hash>/ has a symbolic link per allowed folder. An #include of a folder above
# the layer is then "No such file or directory" at compile time, not a convention. The alternative, one include
# root for every folder plus the script alone, would let a build pass with a wrong include until someone ran the
# script.
#
# strata_layer(<folder> <OBJECT|STATIC> <sources...>) defines the target strata_<folder>.

file(STRINGS "${PROJECT_SOURCE_DIR}/cmake/layers.txt" _strata_layer_lines REGEX "^[a-z_]+:")
set(STRATA_LAYERS "")
foreach(_line IN LISTS _strata_layer_lines)
  string(REGEX MATCH "^([a-z_]+):(.*)$" _ "${_line}")
  set(_name "${CMAKE_MATCH_1}")
  string(REGEX REPLACE "#.*$" "" _deps "${CMAKE_MATCH_2}")
  separate_arguments(_deps UNIX_COMMAND "${_deps}")
  set(_closure ${_name})
  foreach(_dep IN LISTS _deps)
    if(NOT DEFINED STRATA_LAYER_ALLOWED_${_dep})
      message(FATAL_ERROR "cmake/layers.txt: '${_name}' builds on '${_dep}', which is not declared above it")
    endif()
    list(APPEND _closure ${STRATA_LAYER_ALLOWED_${_dep}})
  endforeach()
  list(REMOVE_DUPLICATES _closure)
  set(STRATA_LAYER_ALLOWED_${_name} ${_closure})
  list(APPEND STRATA_LAYERS ${_name})
endforeach()

function(strata_layer name type)
  if(NOT DEFINED STRATA_LAYER_ALLOWED_${name})
    message(FATAL_ERROR "strata_layer(${name}): not declared in cmake/layers.txt")
  endif()
  # The view's name carries a hash of what it holds, so a change to layers.txt gets a fresh view instead of
  # leaving a stale link behind (and nothing here ever deletes through a link into the source tree).
  string(MD5 key "${STRATA_LAYER_ALLOWED_${name}}")
  string(SUBSTRING "${key}" 0 8 key)
  set(view "${CMAKE_BINARY_DIR}/layers/${name}-${key}")
  file(MAKE_DIRECTORY "${view}")
  foreach(folder IN LISTS STRATA_LAYER_ALLOWED_${name})
    if(NOT EXISTS "${view}/${folder}")
      file(CREATE_LINK "${PROJECT_SOURCE_DIR}/${folder}" "${view}/${folder}" SYMBOLIC)
    endif()
  endforeach()
  add_library(strata_${name} ${type} ${ARGN})
  target_include_directories(strata_${name} PRIVATE "${view}")
  target_compile_options(strata_${name} PRIVATE ${STRATA_WARNINGS})
  target_compile_definitions(strata_${name} PUBLIC STRATA_PROFILING=$<BOOL:${STRATA_PROFILING}>)
  set_target_properties(strata_${name} PROPERTIES POSITION_INDEPENDENT_CODE ON)
  strata_unity_batches(strata_${name})
endfunction()

# STRATA_UNITY_BUILD (CMakeLists.txt says why): the target's files compiled in batches of STRATA_UNITY_BATCH_SIZE.
set(STRATA_UNITY_BATCH_SIZE 8 CACHE STRING "Files per unity batch (0: one batch per target, which checks that helper names are unique)")
function(strata_unity_batches target)
  if(STRATA_UNITY_BUILD)
    set_target_properties(${target} PROPERTIES UNITY_BUILD ON UNITY_BUILD_BATCH_SIZE ${STRATA_UNITY_BATCH_SIZE})
  endif()
endfunction()
