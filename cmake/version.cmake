# Bakes the version and the git revision into a generated header, refreshed on every build.
set(MELTLAB_GENERATED_DIR ${PROJECT_BINARY_DIR}/generated)
file(MAKE_DIRECTORY ${MELTLAB_GENERATED_DIR}/meltlab)
add_custom_target(meltlab_version_header
  COMMAND ${CMAKE_COMMAND}
    -DSRC=${PROJECT_SOURCE_DIR} -DOUT=${MELTLAB_GENERATED_DIR}/meltlab/version.h
    -DVERSION=${PROJECT_VERSION}
    -P ${PROJECT_SOURCE_DIR}/cmake/write_version.cmake
  BYPRODUCTS ${MELTLAB_GENERATED_DIR}/meltlab/version.h
  COMMENT "meltlab version header")
