# Writes candela's manual page: the output of `candela help --man`, which is made of the
# --help texts. Run after every link of candela (CMakeLists.txt):
#   cmake -DCANDELA=path/to/candela -DOUT=path/to/candela.1 -P cmake/manpage.cmake
execute_process(COMMAND "${CANDELA}" help --man
                OUTPUT_FILE "${OUT}.tmp"
                RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "candela help --man failed (${status})")
endif()
file(RENAME "${OUT}.tmp" "${OUT}")
