# Third-party dependencies, all from Debian packages.
#   Eigen      : its own CMake config (libeigen3-dev)            host only
#   libmodbus  : pkg-config (libmodbus-dev)                      host only
#   CppUTest   : pkg-config (cpputest); Debian's CMake config    host only
#                for CppUTest is broken, so it is not used.
if(NOT CMAKE_CROSSCOMPILING)
  find_package(Eigen3 3.4 REQUIRED NO_MODULE)
  find_package(PkgConfig REQUIRED)
  pkg_check_modules(LIBMODBUS REQUIRED IMPORTED_TARGET libmodbus)
  pkg_check_modules(CPPUTEST REQUIRED IMPORTED_TARGET cpputest)
  find_package(Threads REQUIRED)
endif()
