# `cmake --install build [--prefix P]`: what a user and another CMake project get.
#   bin/fvm, lib/fvm/ (plugins), lib/python3/dist-packages/fvm*.so, share/man/man1/ (docs/), share/fvm/samples,
#   share/doc/fvm/ (licence, changelog), include/fvm/<module>/*.h, lib/libfvm_*.a (GNUInstallDirs' libdir) and
#   their CMake package lib/cmake/fvm, so that a project writes find_package(fvm) and links fvm::workflows (or
#   any lower layer: fvm::artefacts, fvm::stage, fvm::imaging, fvm::core). tests/install/consumer is such a project.
include(CMakePackageConfigHelpers)

set(fvm_libraries fvm_core fvm_stage fvm_imaging fvm_imaging_opencv fvm_imaging_opencv_on_demand fvm_imaging_zip_xml
  fvm_imaging_zip_xml_on_demand fvm_artefacts fvm_workflows)
foreach(library ${fvm_libraries})
  string(REPLACE "fvm_" "" name ${library})
  set_target_properties(${library} PROPERTIES EXPORT_NAME ${name})
endforeach()
install(TARGETS ${fvm_libraries} EXPORT fvmTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/fvm)
# The headers keep the paths they include each other by ("stage/identification.h").
install(DIRECTORY core stage imaging artefacts workflows DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/fvm
  FILES_MATCHING PATTERN "*.h")

set(fvm_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/fvm)
install(EXPORT fvmTargets NAMESPACE fvm:: DESTINATION ${fvm_cmake_dir})
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/fvmConfig.cmake.in ${PROJECT_BINARY_DIR}/fvmConfig.cmake
  INSTALL_DESTINATION ${fvm_cmake_dir})
# 0.x: a minor release may change the headers.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/fvmConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/fvmConfig.cmake ${PROJECT_BINARY_DIR}/fvmConfigVersion.cmake
  DESTINATION ${fvm_cmake_dir})

install(DIRECTORY ${PROJECT_SOURCE_DIR}/samples/ DESTINATION ${CMAKE_INSTALL_DATADIR}/fvm/samples)
install(FILES ${PROJECT_SOURCE_DIR}/LICENSE ${PROJECT_SOURCE_DIR}/CHANGELOG.md
  DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/fvm)
