# Turns a file into a C++ header holding its bytes, at build time:
#   cmake -DINPUT=file -DOUTPUT=header.h -DSYMBOL=name -P embed_file.cmake
# The header defines `inline constexpr unsigned char SYMBOL[]` (the bytes, then a 0) and
# `inline constexpr std::size_t SYMBOL_size` (without the 0), so the text is also a C string.
foreach(var INPUT OUTPUT SYMBOL)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "embed_file.cmake: -D${var}=... is required")
  endif()
endforeach()
file(READ "${INPUT}" hex HEX)
string(LENGTH "${hex}" hex_length)
math(EXPR size "${hex_length} / 2")
# 32 bytes a line: "0x.., " for each
string(REGEX REPLACE "([0-9a-f][0-9a-f])" "0x\\1," bytes "${hex}")
string(REGEX REPLACE "((0x..,){32})" "\\1\n" bytes "${bytes}")
get_filename_component(name "${INPUT}" NAME)
file(WRITE "${OUTPUT}.tmp"
  "// Generated from ${name} by cmake/embed_file.cmake: do not edit.\n"
  "#pragma once\n#include <cstddef>\n"
  "inline constexpr unsigned char ${SYMBOL}[] = {\n${bytes}0x00};\n"
  "inline constexpr std::size_t ${SYMBOL}_size = ${size};\n")
file(RENAME "${OUTPUT}.tmp" "${OUTPUT}")
