# ctest cli_smoke: `planetsculpt --help` exits 0 and lists every command the sources register,
# and each command's own `--help` exits 0 and shows that command's usage.
# The commands are read from the registrations themselves (the first argument of each
# `add_subcommand(` in src/app/cmd_*.cpp), so the list is never written twice. `live` is built
# only with GLFW and Dear ImGui (LIVE=ON): without them it must be absent.
# Usage: cmake -DEXE=planetsculpt -DSRC=source-dir -DLIVE=ON|OFF -P cli_smoke.cmake
file(GLOB sources ${SRC}/src/app/cmd_*.cpp)
set(commands "")
foreach(source IN LISTS sources)
  file(READ ${source} text)
  string(REGEX MATCHALL "add_subcommand\\([ \t\r\n]*\"[^\"]+\"" calls "${text}")
  foreach(call IN LISTS calls)
    string(REGEX REPLACE ".*\"([^\"]+)\"" "\\1" name "${call}")
    list(APPEND commands ${name})
  endforeach()
endforeach()
list(LENGTH commands count)
if(count LESS 10)
  message(FATAL_ERROR "found only ${count} registered commands in ${SRC}/src/app/cmd_*.cpp: "
                      "${commands} (did the registration change its form?)")
endif()

execute_process(COMMAND ${EXE} --help RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "planetsculpt --help failed: ${rc}\n${err}")
endif()
set(missing "")
foreach(command IN LISTS commands)
  # CLI11 lists each subcommand on a line of its own, indented, then its description.
  string(REGEX MATCH "\n  ${command}[ \t]+[^\n]*[A-Za-z]" listed "${out}")
  if(command STREQUAL "live" AND NOT LIVE)
    if(listed)
      message(FATAL_ERROR "`live` is listed by --help in a build without it:\n${out}")
    endif()
    continue()
  endif()
  if(NOT listed)
    list(APPEND missing ${command})
    continue()
  endif()
  execute_process(COMMAND ${EXE} ${command} --help RESULT_VARIABLE rc OUTPUT_VARIABLE sub
                  ERROR_VARIABLE err)
  if(NOT rc EQUAL 0 OR NOT sub MATCHES "Usage: [^\n]*${command}")
    message(FATAL_ERROR "planetsculpt ${command} --help: exit ${rc}, no usage line of "
                        "`${command}`:\n${sub}${err}")
  endif()
endforeach()
if(missing)
  message(FATAL_ERROR "planetsculpt --help does not list: ${missing}\n--help printed:\n${out}")
endif()
message(STATUS "--help lists all ${count} registered commands: ${commands}")
