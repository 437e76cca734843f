# The CTest fixture around every test (tests/CMakeLists.txt), on the tests' TMPDIR (DIR):
#   MODE=setup  empties DIR (what a killed run left behind) and creates it;
#   MODE=check  fails, naming each entry, if any test left a file or folder in DIR.
if(NOT DIR)
  message(FATAL_ERROR "tmpdir_check.cmake: DIR not set")
endif()
if(MODE STREQUAL "setup")
  file(REMOVE_RECURSE "${DIR}")
  file(MAKE_DIRECTORY "${DIR}")
elseif(MODE STREQUAL "check")
  file(GLOB left LIST_DIRECTORIES true RELATIVE "${DIR}" "${DIR}/*")
  if(left)
    list(LENGTH left count)
    list(JOIN left "\n  " names)
    message(FATAL_ERROR "${count} entries left in the tests' TMPDIR ${DIR} (a test that writes files should use "
                        "tests/temp_dir.h):\n  ${names}")
  endif()
  message(STATUS "tests' TMPDIR ${DIR} is empty")
else()
  message(FATAL_ERROR "tmpdir_check.cmake: MODE must be setup or check, not '${MODE}'")
endif()
