# Every third-party library, found once. Package names: scripts/deps.
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(nlohmann_json 3.10 REQUIRED)
find_package(urdfdom REQUIRED)
find_package(tinyxml2 REQUIRED)  # URDF elements urdfdom drops
find_package(CLI11 REQUIRED)
find_package(Threads REQUIRED)
find_package(TinyGLTF REQUIRED)  # glTF writer (io/gltf), Debian builds it as a shared library
find_package(assimp REQUIRED)  # skinned-character import (io/assimp_import), Debian 5.2.5
# server: Boost.Beast/Asio (header-only in 1.74) and cpp-httplib, which Debian ships compiled: its
# pkg-config -D flags must reach every user or the program crashes (reference/platform.md §2)
find_package(Boost 1.74 REQUIRED)
find_package(PkgConfig REQUIRED)
pkg_check_modules(HTTPLIB REQUIRED IMPORTED_TARGET cpp-httplib)
add_library(pindrag_boost INTERFACE)
target_include_directories(pindrag_boost SYSTEM INTERFACE ${Boost_INCLUDE_DIRS})

# urdfdom's config exposes include dirs and library names as variables
add_library(pindrag_urdfdom INTERFACE)
target_include_directories(pindrag_urdfdom SYSTEM INTERFACE ${urdfdom_INCLUDE_DIRS})
target_link_libraries(pindrag_urdfdom INTERFACE ${urdfdom_LIBRARIES})

if(BUILD_TESTING)
  find_package(GTest REQUIRED)
endif()
if(BUILD_TESTING OR BUILD_BENCHMARKS)
  # oracles and speed peers: MuJoCo (needs libqhull-dev to configure) and KDL
  find_package(mujoco REQUIRED)
  find_package(orocos_kdl REQUIRED)
  add_library(pindrag_kdl INTERFACE)
  target_include_directories(pindrag_kdl SYSTEM INTERFACE ${orocos_kdl_INCLUDE_DIRS})
  # kdl_parser is linked by name: its CMake package drags in ROS tooling
  target_link_libraries(pindrag_kdl INTERFACE kdl_parser ${orocos_kdl_LIBRARIES} Eigen3::Eigen)
endif()
if(BUILD_BENCHMARKS)
  find_package(benchmark REQUIRED)
endif()
