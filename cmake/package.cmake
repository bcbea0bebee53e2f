# The Debian package: `bash run.sh package` (cpack -G DEB in build/) writes build/fvm_<version>_<arch>.deb holding
# everything cmake/install.cmake installs, under /usr. Its dependencies are not listed here: dpkg-shlibdeps reads
# them off the executable, the Python module and the plugins (OpenImageIO, PCL), as Debian's own packages do.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME fvm)
set(CPACK_PACKAGE_VENDOR "the fvm authors")
set(CPACK_PACKAGE_CONTACT "the fvm authors <fvm@users.noreply.github.com>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
    "stage calibration for focus-variation microscopes and laser-tracked machine tools")
string(CONCAT CPACK_PACKAGE_DESCRIPTION
    "fvm identifies the motion-stage error of a focus-variation microscope from two measurements of an\n"
    "uncalibrated artefact, one stitched and one stitching-free, and compensates later stitching-free scans.\n"
    "The same kinematics engine verifies machine tools measured with laser trackers. Includes the fvm command,\n"
    "its man pages, the Python module (import fvm), sample data, and the C++ libraries with their CMake\n"
    "package (find_package(fvm)).")
set(CPACK_RESOURCE_FILE_LICENSE ${PROJECT_SOURCE_DIR}/LICENSE)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)  # fvm_<version>_<arch>.deb
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# The Python module links no libpython (no shared-library dependency says it): the interpreter and numpy are
# recommended, the command needs neither.
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "python3, python3-numpy")
set(CPACK_OUTPUT_FILE_PREFIX ${PROJECT_BINARY_DIR})
set(CPACK_STRIP_FILES ON)
include(CPack)
