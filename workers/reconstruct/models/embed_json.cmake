# SPDX-License-Identifier: Apache-2.0
# Embeds a JSON file in C++ as a string constant, so binaries need no data files at run time.
# cmake -DIN=model.json -DOUT=model_data.cc -DNAMESPACE=ns -DSYMBOL=kName -P embed_json.cmake
file(READ "${IN}" content)
string(FIND "${content}" ")vbjson\"" clash)
if(NOT clash EQUAL -1)
  message(FATAL_ERROR "${IN} contains the raw string delimiter )vbjson\"")
endif()
file(WRITE "${OUT}.tmp"
  "// Generated from ${IN} by embed_json.cmake; do not edit.\n"
  "namespace ${NAMESPACE} {\n"
  "extern const char* const ${SYMBOL};\n"
  "const char* const ${SYMBOL} = R\"vbjson(${content})vbjson\";\n"
  "}  // namespace ${NAMESPACE}\n")
file(RENAME "${OUT}.tmp" "${OUT}")
