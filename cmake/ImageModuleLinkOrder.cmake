# candela_image_link_order(<out-var> <library>): the libraries of cmake/image_module_link_order.txt
# that <library> (OpenImageIO) loads here, as resolved paths in the list's order. The image
# module names them first among its needed libraries, which puts them first in the dynamic
# loader's search list when the module is loaded: most symbol look-ups of OpenImageIO's libraries
# then end early (tools/image_module_link_order.py says how the list is made and why). Naming a
# library OpenImageIO loads anyway adds nothing to the load; one it does not load is left out.
function(candela_image_link_order out_var library)
  set(paths "")
  find_program(CANDELA_LDD ldd)
  if(CANDELA_LDD)
    execute_process(COMMAND ${CANDELA_LDD} ${library} OUTPUT_VARIABLE loaded
                    RESULT_VARIABLE ldd_result ERROR_QUIET)
  endif()
  if(NOT CANDELA_LDD OR NOT ldd_result EQUAL 0)
    message(STATUS "candela: image module link order: cannot list the libraries of ${library}")
    set(${out_var} "" PARENT_SCOPE)
    return()
  endif()
  file(STRINGS ${PROJECT_SOURCE_DIR}/cmake/image_module_link_order.txt names REGEX "^[^#]")
  # ldd leaves out the library itself: a name is that library when the file of that name
  # beside it is the same file.
  get_filename_component(self ${library} REALPATH)
  get_filename_component(self_dir ${library} DIRECTORY)
  set(found 0)
  foreach(name IN LISTS names)
    string(REGEX REPLACE "([][+.*()^$?|\\\\])" "\\\\\\1" pattern "${name}")
    string(REGEX MATCH "[\t ]${pattern} => ([^ ]+) " hit "${loaded}")
    get_filename_component(beside "${self_dir}/${name}" REALPATH)
    if(hit)
      list(APPEND paths ${CMAKE_MATCH_1})
      math(EXPR found "${found} + 1")
    elseif(beside STREQUAL self)
      list(APPEND paths ${self_dir}/${name})
      math(EXPR found "${found} + 1")
    endif()
  endforeach()
  list(LENGTH names listed)
  message(STATUS "candela: image module link order: ${found} of ${listed} libraries named first")
  set(${out_var} ${paths} PARENT_SCOPE)
endfunction()
