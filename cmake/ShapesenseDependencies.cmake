# Finds every dependency of the system. A missing one stops the configure with
# the Debian package that provides it; deploy/install-deps.sh installs them all.

function(shapesense_require found package what)
  if(NOT ${found})
    message(FATAL_ERROR
      "shapesense: ${what} not found. Install the Debian package '${package}' "
      "(or run: sudo deploy/install-deps.sh).")
  endif()
endfunction()

find_package(PkgConfig QUIET)
shapesense_require(PkgConfig_FOUND pkg-config "pkg-config")

find_package(Eigen3 3.3 QUIET NO_MODULE)
shapesense_require(Eigen3_FOUND libeigen3-dev "Eigen 3")

find_package(OpenCV QUIET COMPONENTS core imgproc imgcodecs calib3d videoio aruco)
shapesense_require(OpenCV_FOUND "libopencv-dev libopencv-contrib-dev" "OpenCV (core, imgproc, imgcodecs, calib3d, videoio, aruco)")

find_package(Ceres QUIET)
shapesense_require(Ceres_FOUND libceres-dev "Ceres Solver")

find_package(yaml-cpp QUIET)
shapesense_require(yaml-cpp_FOUND libyaml-cpp-dev "yaml-cpp")

find_package(CLI11 QUIET)
shapesense_require(CLI11_FOUND libcli11-dev "CLI11")

find_package(spdlog QUIET)
shapesense_require(spdlog_FOUND libspdlog-dev "spdlog")

find_package(nlohmann_json QUIET)
shapesense_require(nlohmann_json_FOUND nlohmann-json3-dev "nlohmann-json")

# LCM 1.3 ships only a pkg-config file.
pkg_check_modules(LCM QUIET IMPORTED_TARGET lcm)
shapesense_require(LCM_FOUND "liblcm-dev" "LCM")
find_program(LCM_GEN lcm-gen)
shapesense_require(LCM_GEN "liblcm-bin" "lcm-gen")

pkg_check_modules(ARAVIS QUIET IMPORTED_TARGET aravis-0.8)
shapesense_require(ARAVIS_FOUND "libaravis-dev libusb-1.0-0-dev" "Aravis 0.8")

pkg_check_modules(LIBV4L2 QUIET IMPORTED_TARGET libv4l2)
shapesense_require(LIBV4L2_FOUND "libv4l-dev" "libv4l2")

# sd_notify for the services' readiness and watchdog under systemd.
pkg_check_modules(LIBSYSTEMD QUIET IMPORTED_TARGET libsystemd)
shapesense_require(LIBSYSTEMD_FOUND "libsystemd-dev" "libsystemd")

# HMAC-SHA256 for the messages that move the robot (libs/security).
find_package(OpenSSL QUIET COMPONENTS Crypto)
shapesense_require(OPENSSL_FOUND "libssl-dev" "OpenSSL (libcrypto)")

# Boost.Beast and Asio (header-only): the web monitor's HTTP and WebSocket
# server (docs/monitor.md), and the WebSocket clients of its tests.
find_package(Boost 1.74 QUIET)
shapesense_require(Boost_FOUND libboost-dev "Boost 1.74 (Beast, Asio)")

if(SHAPESENSE_BUILD_TESTS)
  find_package(GTest QUIET)
  shapesense_require(GTest_FOUND "libgtest-dev libgmock-dev" "GoogleTest")
endif()
if(SHAPESENSE_BUILD_BENCH)
  find_package(benchmark QUIET)
  shapesense_require(benchmark_FOUND "libbenchmark-dev" "Google Benchmark")
endif()
