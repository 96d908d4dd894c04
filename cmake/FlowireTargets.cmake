# Compiler warnings for every flowire target.
add_library(flowire_warnings INTERFACE)
target_compile_options(flowire_warnings INTERFACE
  $<$<CXX_COMPILER_ID:GNU,Clang>:-Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor
    -Wold-style-cast -Wcast-align -Woverloaded-virtual -Wimplicit-fallthrough>
  $<$<BOOL:${FLOWIRE_WARNINGS_AS_ERRORS}>:-Werror>)

set(FLOWIRE_EXPORTED_TARGETS "" CACHE INTERNAL "")

# flowire_add_module(NAME SOURCES ... PUBLIC_DEPS ... PRIVATE_DEPS ...)
# Creates library flowire_<NAME> with alias flowire::<NAME>, headers in <NAME>/include.
function(flowire_add_module name)
  cmake_parse_arguments(M "" "" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(flowire_${name} ${M_SOURCES})
  add_library(flowire::${name} ALIAS flowire_${name})
  set_target_properties(flowire_${name} PROPERTIES EXPORT_NAME ${name} OUTPUT_NAME flowire_${name})
  target_include_directories(flowire_${name} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_link_libraries(flowire_${name} PUBLIC ${M_PUBLIC_DEPS} PRIVATE ${M_PRIVATE_DEPS}
    $<BUILD_INTERFACE:flowire_warnings>)
  set(FLOWIRE_EXPORTED_TARGETS ${FLOWIRE_EXPORTED_TARGETS} flowire_${name} CACHE INTERNAL "")
  install(DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endfunction()
