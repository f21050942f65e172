# Looks for what the Python module needs (python/CMakeLists.txt builds it) and sets VKMESH_PYTHON_FOUND.
# The interpreter is Debian's /usr/bin/python3 unless -DPython3_EXECUTABLE=... names another: a python3
# earlier on PATH (pyenv, a virtual environment) usually lacks python3-numpy and would make the module
# vanish, or be built for a Python that Debian's packages do not serve.
if(NOT DEFINED Python3_EXECUTABLE AND EXISTS /usr/bin/python3)
  set(Python3_EXECUTABLE /usr/bin/python3 CACHE FILEPATH "Python interpreter the vkmesh module is built for")
endif()
find_package(Python3 3.9 COMPONENTS Interpreter Development.Module NumPy)
if(Python3_FOUND)
  # pybind11's CMake package (pybind11-dev) uses the Python3 found above (its FindPython mode).
  find_package(pybind11 2.6 CONFIG QUIET)
endif()
if(Python3_FOUND AND pybind11_FOUND)
  set(VKMESH_PYTHON_FOUND TRUE)
  message(STATUS "vkmesh: building the Python module for ${Python3_EXECUTABLE} (Python ${Python3_VERSION}, "
                 "numpy ${Python3_NumPy_VERSION}, pybind11 ${pybind11_VERSION})")
else()
  set(missing "")
  if(NOT Python3_Interpreter_FOUND)
    list(APPEND missing "python3")
  endif()
  if(NOT Python3_Development.Module_FOUND)
    list(APPEND missing "python3-dev")
  endif()
  if(NOT Python3_NumPy_FOUND)
    list(APPEND missing "python3-numpy")
  endif()
  if(Python3_FOUND AND NOT pybind11_FOUND)
    list(APPEND missing "pybind11-dev")
  endif()
  list(JOIN missing " " missing)
  message(STATUS "vkmesh: not building the Python module: missing ${missing} "
                 "(scripts/install_deps.sh installs them; -DVKMESH_BUILD_PYTHON=OFF silences this)")
endif()
