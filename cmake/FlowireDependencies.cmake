# Every dependency is a Debian 12 package (scripts/install-deps.sh); nothing is downloaded.
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(yaml-cpp REQUIRED)
find_package(nlohmann_json 3.10 REQUIRED)
find_package(CLI11 REQUIRED)
find_package(fmt REQUIRED)
find_package(Threads REQUIRED)
find_package(PkgConfig REQUIRED)

# SuiteSparse 5.x on Debian ships neither a CMake config nor a .pc file.
find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse REQUIRED)
foreach(lib cholmod amd colamd camd ccolamd suitesparseconfig)
  find_library(SUITESPARSE_${lib}_LIBRARY ${lib} REQUIRED)
endforeach()
if(NOT TARGET flowire_cholmod)
  add_library(flowire_cholmod INTERFACE)
  target_include_directories(flowire_cholmod SYSTEM INTERFACE ${CHOLMOD_INCLUDE_DIR})
  target_link_libraries(flowire_cholmod INTERFACE
    ${SUITESPARSE_cholmod_LIBRARY} ${SUITESPARSE_amd_LIBRARY} ${SUITESPARSE_colamd_LIBRARY}
    ${SUITESPARSE_camd_LIBRARY} ${SUITESPARSE_ccolamd_LIBRARY}
    ${SUITESPARSE_suitesparseconfig_LIBRARY})
endif()

# BLAS (whichever the system selects: scripts/install-deps.sh installs OpenBLAS) for the few
# dense products called directly (the wall's contact compliance); CHOLMOD uses it too.
find_package(BLAS REQUIRED)
# OpenMP's runtime (GCC's libgomp, which CHOLMOD already loads): the wall asks it for teams no
# larger than the free cores (solid/src/elastic_solid.cpp).
find_package(OpenMP REQUIRED COMPONENTS CXX)

if(FLOWIRE_WITH_VTK)
  find_package(VTK 9.1 REQUIRED COMPONENTS
    CommonCore CommonDataModel IOXML IOLegacy IOGeometry FiltersCore FiltersSources
    FiltersGeneral RenderingCore RenderingOpenGL2 RenderingFreeType InteractionStyle
    RenderingAnnotation IOImage ChartsCore ViewsContext2D RenderingContext2D RenderingContextOpenGL2)
endif()

if(FLOWIRE_WITH_PETSC OR FLOWIRE_WITH_FEM)
  find_package(MPI COMPONENTS C CXX)
  pkg_check_modules(PETSC IMPORTED_TARGET PETSc>=3.18)
  if(NOT (MPI_FOUND AND PETSC_FOUND))
    message(STATUS "flowire: PETSc/MPI not found: the petsc solver and the FEM path are off")
    set(FLOWIRE_WITH_PETSC OFF)
    set(FLOWIRE_WITH_FEM OFF)
  endif()
endif()

if(FLOWIRE_WITH_FEM)
  find_path(GMSH_INCLUDE_DIR gmsh.h)
  find_library(GMSH_LIBRARY gmsh)
  if(GMSH_INCLUDE_DIR AND GMSH_LIBRARY)
    add_library(flowire_gmsh INTERFACE)
    target_include_directories(flowire_gmsh SYSTEM INTERFACE ${GMSH_INCLUDE_DIR})
    target_link_libraries(flowire_gmsh INTERFACE ${GMSH_LIBRARY})
  else()
    message(STATUS "flowire: gmsh not found: the FEM path is off")
    set(FLOWIRE_WITH_FEM OFF)
  endif()
endif()

# The Python module is built for Debian's own python3 (its numpy, its dist-packages), not
# for another python3 first on PATH: -DPython3_EXECUTABLE=... chooses another.
if(FLOWIRE_WITH_PYTHON AND CMAKE_CXX_FLAGS MATCHES "-fsanitize")
  # python3 would have to preload the sanitizer runtime to load the module.
  message(STATUS "flowire: the Python module is off in a sanitizer build")
  set(FLOWIRE_WITH_PYTHON OFF)
endif()
if(FLOWIRE_WITH_PYTHON)
  if(NOT Python3_EXECUTABLE AND EXISTS /usr/bin/python3)
    set(Python3_EXECUTABLE /usr/bin/python3 CACHE FILEPATH "Python the flowire module is built for")
  endif()
  find_package(Python3 COMPONENTS Interpreter Development.Module)
  if(Python3_FOUND)
    find_package(pybind11 CONFIG)
  endif()
  if(NOT (Python3_FOUND AND pybind11_FOUND))
    message(STATUS "flowire: pybind11 or the Python headers not found: the Python module is off")
    set(FLOWIRE_WITH_PYTHON OFF)
  endif()
endif()
