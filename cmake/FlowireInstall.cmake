include(CMakePackageConfigHelpers)
install(TARGETS ${FLOWIRE_EXPORTED_TARGETS} EXPORT flowireTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(TARGETS flowire_cholmod flowire_warnings EXPORT flowireTargets)
if(TARGET flowire_gmsh)
  install(TARGETS flowire_gmsh EXPORT flowireTargets)
endif()
install(EXPORT flowireTargets NAMESPACE flowire:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/flowire)
configure_package_config_file(${CMAKE_CURRENT_SOURCE_DIR}/cmake/flowireConfig.cmake.in
  ${CMAKE_CURRENT_BINARY_DIR}/flowireConfig.cmake
  INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/flowire)
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/flowireConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/flowireConfig.cmake
  ${CMAKE_CURRENT_BINARY_DIR}/flowireConfigVersion.cmake
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/flowire)
