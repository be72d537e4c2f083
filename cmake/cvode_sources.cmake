# The part of SUNDIALS 6.4.1 (Debian's source package, BSD-3-Clause) that the FMU needs: CVODE
# with the serial N_Vector, dense and band matrices, the dense linear solver and the Newton
# nonlinear solver (not the profiler: it is off, and its file needs POSIX or MPI timers). The lists were found by linking the FMU with -z defs against these files alone
# and taking gcc -MM's headers; tests/platforms/test_sources.py rebuilds the binary from them.
# Paths are relative to the SUNDIALS source tree; impact_stage_sources() copies them into an
# FMU's sources/ so that `-I sources` alone resolves every #include:
#   public headers    include/<module>/x.h -> sources/<module>/x.h   (#include <module/x.h>)
#   sources           src/<module>/[sub/]x.c -> sources/<module>/x.c
#   private headers   src/sundials/*.h -> sources/*.h (#include "x.h" from any module),
#                     src/cvode/*.h -> sources/cvode/
set(CVODE_SOURCES
  src/cvode/cvode.c src/cvode/cvode_io.c src/cvode/cvode_ls.c src/cvode/cvode_nls.c
  src/cvode/cvode_proj.c
  src/sundials/sundials_context.c src/sundials/sundials_logger.c src/sundials/sundials_math.c
  src/sundials/sundials_matrix.c src/sundials/sundials_linearsolver.c
  src/sundials/sundials_nonlinearsolver.c src/sundials/sundials_nvector.c
  src/sundials/sundials_nvector_senswrapper.c src/sundials/sundials_dense.c
  src/sundials/sundials_futils.c src/sundials/sundials_version.c
  src/nvector/serial/nvector_serial.c src/sunmatrix/dense/sunmatrix_dense.c
  src/sunmatrix/band/sunmatrix_band.c src/sunlinsol/dense/sunlinsol_dense.c
  src/sunnonlinsol/newton/sunnonlinsol_newton.c)
set(CVODE_PUBLIC_HEADERS
  cvode/cvode.h cvode/cvode_ls.h cvode/cvode_proj.h nvector/nvector_serial.h
  sundials/sundials_context.h sundials/sundials_dense.h sundials/sundials_direct.h
  sundials/sundials_iterative.h sundials/sundials_linearsolver.h sundials/sundials_logger.h
  sundials/sundials_math.h sundials/sundials_matrix.h sundials/sundials_nonlinearsolver.h
  sundials/sundials_nvector.h sundials/sundials_profiler.h sundials/sundials_types.h
  sundials/sundials_version.h sundials/sundials_futils.h sundials/sundials_nvector_senswrapper.h
  sunlinsol/sunlinsol_dense.h sunmatrix/sunmatrix_band.h sunmatrix/sunmatrix_dense.h
  sunmatrix/sunmatrix_sparse.h sunnonlinsol/sunnonlinsol_newton.h)
set(CVODE_PRIVATE_HEADERS
  src/sundials/sundials_context_impl.h src/sundials/sundials_debug.h
  src/sundials/sundials_hashmap.h src/sundials/sundials_logger_impl.h src/sundials/sundials_utils.h
  src/cvode/cvode_impl.h src/cvode/cvode_ls_impl.h src/cvode/cvode_proj_impl.h)

# Where a file of the SUNDIALS tree goes in sources/ (see above).
function(cvode_staged_name path out)
  get_filename_component(name ${path} NAME)
  if(path MATCHES "^src/sundials/.*\\.h$")
    set(${out} ${name} PARENT_SCOPE)
  else()
    string(REGEX MATCH "^src/([a-z]+)/" _ ${path})
    set(${out} ${CMAKE_MATCH_1}/${name} PARENT_SCOPE)
  endif()
endfunction()

# The CVODE .c files as they are named in sources/ (for <SourceFiles> / buildDescription.xml).
set(CVODE_STAGED_SOURCES)
foreach(f ${CVODE_SOURCES})
  cvode_staged_name(${f} staged)
  list(APPEND CVODE_STAGED_SOURCES ${staged})
endforeach()
