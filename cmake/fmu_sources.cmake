# The FMU's own C sources beside its FMI interface file (fmi2.c or fmi3.c): one list for the
# binaries (fmu_src/CMakeLists.txt) and for the sources/ the archives ship with their build
# description (stage_sources.cmake). The FMI core, one unit per concern (fmu_core.h), the
# steppers (stepper.h) and the model.
set(IMPACT_MODEL_SOURCES
  fmu_core.c fmu_states.c fmu_vars.c fmu_snapshot.c fmu_cs.c fmu_me.c fmu_derivatives.c
  stepper.c stepper_methods.c solver_cvode.c closed_form.c sens.c model.c)
