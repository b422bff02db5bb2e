# Writes candela's bash completion script: the output of `candela completion bash`, made from
# the option table of --help. Run after every link of candela (CMakeLists.txt):
#   cmake -DCANDELA=path/to/candela -DOUT=path/to/candela.bash -P cmake/completion.cmake
execute_process(COMMAND "${CANDELA}" completion bash
                OUTPUT_FILE "${OUT}.tmp"
                RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "candela completion bash failed (${status})")
endif()
file(RENAME "${OUT}.tmp" "${OUT}")
