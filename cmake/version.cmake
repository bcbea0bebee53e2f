# Writes the source that defines fvm::Version() and fvm::GitCommit() (core/version.h), run at every build by the
# target fvm_version_source: cheap (one git call), and configure_file leaves the file untouched when nothing
# changed, so that nothing recompiles. Inputs: SOURCE_DIR, VERSION, OUTPUT.
set(FVM_VERSION_TEXT "${VERSION}")
set(FVM_GIT_COMMIT "unknown")
find_program(GIT git)
if(GIT AND EXISTS "${SOURCE_DIR}/.git")
  execute_process(COMMAND "${GIT}" -C "${SOURCE_DIR}" rev-parse --short=12 HEAD
    OUTPUT_VARIABLE commit OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET RESULT_VARIABLE failed)
  if(NOT failed AND commit)
    set(FVM_GIT_COMMIT "${commit}")
    # Tracked files changed since the commit: the binary is not that commit.
    execute_process(COMMAND "${GIT}" -C "${SOURCE_DIR}" diff --quiet HEAD -- RESULT_VARIABLE dirty
      OUTPUT_QUIET ERROR_QUIET)
    if(dirty EQUAL 1)
      string(APPEND FVM_GIT_COMMIT "-dirty")
    endif()
  endif()
endif()
configure_file("${CMAKE_CURRENT_LIST_DIR}/version.cc.in" "${OUTPUT}" @ONLY)
