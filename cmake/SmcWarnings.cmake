# Warnings on for every project target; errors when SMC_WERROR is set (CI).
function(smc_target_warnings target)
  target_compile_options(${target} PRIVATE
    $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor
      -Wold-style-cast -Wcast-align -Woverloaded-virtual -Wconversion
      -Wsign-conversion -Wnull-dereference -Wdouble-promotion -Wformat=2
      -Wimplicit-fallthrough
      -Wno-missing-field-initializers>
    $<$<AND:$<COMPILE_LANGUAGE:CXX>,$<BOOL:${SMC_WERROR}>>:-Werror>)
endfunction()

# One library per folder: smc_add_library(smc_common SOURCES ... DEPS ...)
# Public headers live under <folder>/include/smc/<area>/.
function(smc_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(${name} ${ARG_SOURCES})
  target_include_directories(${name} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
  target_link_libraries(${name} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  smc_target_warnings(${name})
endfunction()
