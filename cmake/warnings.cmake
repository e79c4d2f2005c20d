# Warnings for the project's own targets (third-party headers come in as SYSTEM includes).
add_library(pindrag_warnings INTERFACE)
target_compile_options(pindrag_warnings INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wimplicit-fallthrough -Wvla -Werror)

# pindrag_target(<name>): applies the project's warnings to a target
function(pindrag_target name)
  target_link_libraries(${name} PRIVATE pindrag_warnings)
endfunction()
