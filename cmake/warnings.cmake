# Warnings for the project's own targets (third-party headers come in as SYSTEM includes).
add_library(pindrag_warnings INTERFACE)
target_compile_options(pindrag_warnings INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wimplicit-fallthrough -Wvla -Werror)

# pindrag_target(<name>): applies the project's warnings to a target
function(pindrag_target name)
  target_link_libraries(${name} PRIVATE pindrag_warnings)
endfunction()

# GCC 12 reports false -Wrestrict overlaps inside libstdc++'s std::string concatenation at -O3
# (GCC bug 105651); the warning is not about our code, so it is off for that compiler.
if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
  target_compile_options(pindrag_warnings INTERFACE -Wno-restrict)
endif()

# With -fsanitize, GCC's flow analysis reports -Wmaybe-uninitialized inside libstdc++ (std::regex,
# std::function moves) that are not reachable bugs (GCC documents that the sanitizers make this
# warning unreliable). Sanitizer builds keep every other warning as an error.
if(ENABLE_SANITIZERS AND CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
  target_compile_options(pindrag_warnings INTERFACE -Wno-maybe-uninitialized)
endif()
