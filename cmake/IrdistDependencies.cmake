# The modules' dependencies, all Debian packages found through imported targets; included by the
# top CMakeLists.txt and by fuzz/CMakeLists.txt, which builds the same module libraries.
find_package(PkgConfig REQUIRED)
pkg_check_modules(ARAVIS REQUIRED IMPORTED_TARGET aravis-0.8)
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(Ceres REQUIRED)
find_package(OpenCV REQUIRED COMPONENTS core imgproc imgcodecs highgui calib3d)
find_package(yaml-cpp REQUIRED)
find_package(Boost REQUIRED)
find_package(CLI11 CONFIG REQUIRED)
find_package(Threads REQUIRED)
find_package(OpenSSL REQUIRED COMPONENTS Crypto)  # SHA-256 of recorded frames (libssl-dev)
