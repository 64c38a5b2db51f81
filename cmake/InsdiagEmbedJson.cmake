# insdiag_embed_json(PREFIX TEMPLATE OUTPUT FILE...) — configures TEMPLATE into
# OUTPUT with @PREFIX_COUNT@, the number of FILEs, and @PREFIX_LITERALS@, their
# contents as C++ raw string literals, one a line: the built-in data files
# (data/*/*.json) compiled into the libraries that read them. Editing a file
# re-runs the configure step.
function(insdiag_embed_json prefix template output)
  set(${prefix}_LITERALS "")
  foreach(f IN LISTS ARGN)
    file(READ ${f} content)
    string(APPEND ${prefix}_LITERALS "    R\"insdiag_json(${content})insdiag_json\",\n")
  endforeach()
  list(LENGTH ARGN ${prefix}_COUNT)
  set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${ARGN})
  configure_file(${template} ${output} @ONLY)
endfunction()
