# keygrid_add_library(<name> [SHARED] SOURCES ... [PUBLIC_DEPS ...] [PRIVATE_DEPS ...])
# Creates target keygrid_<name> with ALIAS keygrid::<name>, headers in
# libs/<name>/include/keygrid/<name>/, warnings on, and installs it into the export set.
function(keygrid_add_library name)
  cmake_parse_arguments(ARG "SHARED" "" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  if(ARG_SHARED)
    add_library(keygrid_${name} SHARED ${ARG_SOURCES})
  else()
    add_library(keygrid_${name} ${ARG_SOURCES})
  endif()
  add_library(keygrid::${name} ALIAS keygrid_${name})
  set_target_properties(keygrid_${name} PROPERTIES
    EXPORT_NAME ${name}
    POSITION_INDEPENDENT_CODE ON
    VERSION ${PROJECT_VERSION}
    SOVERSION ${PROJECT_VERSION_MAJOR}.${PROJECT_VERSION_MINOR}
    INSTALL_RPATH "$ORIGIN")
  target_include_directories(keygrid_${name} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_compile_features(keygrid_${name} PUBLIC cxx_std_17)
  target_compile_options(keygrid_${name} PRIVATE -Wall -Wextra)
  target_link_libraries(keygrid_${name} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  if(KEYGRID_SANITIZE)
    # Instrumented libraries need the sanitizer runtimes in whatever links them (also consumers).
    target_link_options(keygrid_${name} INTERFACE -fsanitize=address,undefined)
  endif()
  install(TARGETS keygrid_${name} EXPORT keygridTargets
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
    RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  install(DIRECTORY include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endfunction()

# keygrid_add_app(<exe-name> SOURCES ... DEPS ...): a thin executable, installed.
function(keygrid_add_app name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_compile_options(${name} PRIVATE -Wall -Wextra)
  target_link_libraries(${name} PRIVATE ${ARG_DEPS})
  # Installed: the keygrid libraries are found next to the tool's folder, wherever the prefix is.
  set_target_properties(${name} PROPERTIES
    RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/bin
    INSTALL_RPATH "$ORIGIN/${KEYGRID_BIN_TO_LIB}")
  install(TARGETS ${name} EXPORT keygridTargets RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endfunction()
