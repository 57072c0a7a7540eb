# pneumo_add_plugin(<target> <source>...)
# A component plugin: a shared module (no "lib" prefix, so `plugins:
# [my_components.so]` names the file) built with the flags pneumo was built
# with (C++20), linked to pneumo::components. Its sources define the entry
# point with PNEUMO_PLUGIN (framework/plugin/plugin_api.hpp).
function(pneumo_add_plugin target)
  add_library(${target} MODULE ${ARGN})
  target_link_libraries(${target} PRIVATE pneumo::components)
  target_compile_features(${target} PRIVATE cxx_std_20)
  set_target_properties(${target} PROPERTIES PREFIX "" CXX_EXTENSIONS OFF)
endfunction()
