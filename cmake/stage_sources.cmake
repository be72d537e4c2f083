# cmake -P script: writes an FMU's sources/ (and, for FMI 2.0, the modelDescription.xml with its
# <SourceFiles>; for FMI 3.0, sources/buildDescription.xml), so that the FMU builds on a machine
# with only a C compiler: fmpy's build_platform_binary (-I sources, the listed .c files) or
# `cmake -S sources` (sources/CMakeLists.txt). Arguments (-D):
#   FMI          2 or 3
#   FMU_SRC      fmu_src/ (the model's C sources, headers, include/fmi2|fmi3, modelDescription)
#   SUNDIALS_SRC Debian's SUNDIALS source tree (scripts/sundials_source.sh)
#   SUNDIALS_GEN an installed CVODE's include/ (its generated sundials_config.h, sundials_export.h)
#   OUT          the FMU's staging folder (gets sources/, documentation/licenses/, modelDescription.xml)
cmake_minimum_required(VERSION 3.16)
include(${CMAKE_CURRENT_LIST_DIR}/cvode_sources.cmake)
include(${CMAKE_CURRENT_LIST_DIR}/fmu_sources.cmake)

set(src ${OUT}/sources)
file(REMOVE_RECURSE ${src})
file(MAKE_DIRECTORY ${src})

# --- the model ------------------------------------------------------------------------------
if(FMI EQUAL 2)
  set(interface_c fmi2.c)
else()
  set(interface_c fmi3.c)
endif()
set(model_c ${interface_c} ${IMPACT_MODEL_SOURCES})
# *.inc: the generated variable table and defaults (fmu_src/generate_variables.py)
file(GLOB model_h RELATIVE ${FMU_SRC} ${FMU_SRC}/*.h ${FMU_SRC}/*.inc)
foreach(f ${model_c} ${model_h})
  file(COPY ${FMU_SRC}/${f} DESTINATION ${src})
endforeach()
# The FMI headers, for the plain CMake build only: an importer compiles with its own (the
# standard asks it to), and they are not on fmpy's include path (sources/ alone).
file(COPY ${FMU_SRC}/include/fmi${FMI}/ DESTINATION ${src}/fmi-headers)

# --- CVODE ----------------------------------------------------------------------------------
foreach(f ${CVODE_SOURCES} ${CVODE_PRIVATE_HEADERS})
  cvode_staged_name(${f} staged)
  configure_file(${SUNDIALS_SRC}/${f} ${src}/${staged} COPYONLY)
endforeach()
foreach(h ${CVODE_PUBLIC_HEADERS})
  configure_file(${SUNDIALS_SRC}/include/${h} ${src}/${h} COPYONLY)
endforeach()
# The generated configuration, made compiler-neutral: deprecation attributes for MSVC and GCC/Clang
# alike, and no POSIX timers (only SUNDIALS' profiler, which is off, uses them).
foreach(h sundials_config.h sundials_export.h)
  file(READ ${SUNDIALS_GEN}/sundials/${h} text)
  string(REGEX REPLACE "(#  define SUNDIALS_DEPRECATED(_MSG\\(msg\\))?) __attribute__ \\(\\(__deprecated__(\\(msg\\))?\\)\\)"
         "#  if defined(_MSC_VER)\n\\1 __declspec(deprecated\\3)\n#  else\n\\1 __attribute__ ((__deprecated__\\3))\n#  endif"
         text "${text}")
  string(REPLACE "\n#define SUNDIALS_HAVE_POSIX_TIMERS\n" "\n/* #undef SUNDIALS_HAVE_POSIX_TIMERS (only the profiler, which is off, uses it) */\n" text "${text}")
  file(WRITE ${src}/sundials/${h} "${text}")
endforeach()
file(MAKE_DIRECTORY ${OUT}/documentation/licenses)
configure_file(${SUNDIALS_SRC}/LICENSE ${OUT}/documentation/licenses/SUNDIALS-LICENSE.txt COPYONLY)
configure_file(${SUNDIALS_SRC}/NOTICE ${OUT}/documentation/licenses/SUNDIALS-NOTICE.txt COPYONLY)
file(WRITE ${OUT}/documentation/licenses/license.txt
  "The model (sources/*.c, *.h, *.inc at the top of sources/) is part of impact-grazing.\n"
  "sources/cvode, sundials, nvector, sunmatrix, sunlinsol, sunnonlinsol and the sundials_*.h files\n"
  "at the top of sources/ are SUNDIALS 6.4.1 (Debian's source package), BSD-3-Clause:\n"
  "see SUNDIALS-LICENSE.txt and SUNDIALS-NOTICE.txt. The binaries link the same CVODE statically.\n")

# --- the build descriptions -----------------------------------------------------------------
set(all_c ${model_c} ${CVODE_STAGED_SOURCES})
set(files_xml "")  # FMI 2.0 <SourceFiles><File>, FMI 3.0 <SourceFileSet><SourceFile>
if(FMI EQUAL 2)
  set(file_element File)
else()
  set(file_element SourceFile)
endif()
foreach(f ${all_c})
  string(APPEND files_xml "      <${file_element} name=\"${f}\"/>\n")
endforeach()
string(REPLACE ";" " " all_c_str "${all_c}")
file(WRITE ${src}/sources.cmake "# The .c files of this FMU (written by the exporter's cmake/stage_sources.cmake).\nset(FMU_FMI_VERSION ${FMI})\nset(FMU_SOURCES ${all_c_str})\n")
configure_file(${CMAKE_CURRENT_LIST_DIR}/sources_CMakeLists.txt ${src}/CMakeLists.txt COPYONLY)

if(FMI EQUAL 2)
  # <SourceFiles> in both interfaces' elements (FMI 2.0, 2.2.1 / 3.3.1 / 4.3.1).
  file(READ ${FMU_SRC}/modelDescription.xml md)
  set(sf "    <SourceFiles>\n${files_xml}    </SourceFiles>\n")
  string(REGEX REPLACE "(<ModelExchange[^>]*)/>" "\\1>\n${sf}  </ModelExchange>" md "${md}")
  string(REGEX REPLACE "(<CoSimulation[^>]*)/>" "\\1>\n${sf}  </CoSimulation>" md "${md}")
  file(WRITE ${OUT}/modelDescription.xml "${md}")
else()
  file(WRITE ${src}/buildDescription.xml
"<?xml version=\"1.0\" encoding=\"UTF-8\"?>
<fmiBuildDescription fmiVersion=\"3.0\">
  <BuildConfiguration modelIdentifier=\"ImpactOscillator\" description=\"the model and CVODE (SUNDIALS 6.4.1), C99, one shared library\">
    <SourceFileSet language=\"C99\">
${files_xml}    </SourceFileSet>
    <Library name=\"m\" external=\"true\" description=\"the C math library (Unix)\"/>
  </BuildConfiguration>
</fmiBuildDescription>
")
  configure_file(${FMU_SRC}/modelDescription3.xml ${OUT}/modelDescription.xml COPYONLY)
endif()
