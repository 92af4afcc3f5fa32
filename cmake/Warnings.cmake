# Warnings for our own targets only (never for imported ones), and sanitizers for everything.
add_library(dfbwall_warnings INTERFACE)
target_compile_options(dfbwall_warnings INTERFACE -Wall -Wextra -Wpedantic -Wshadow
                       -Wnon-virtual-dtor -Wold-style-cast -Wcast-align -Wnull-dereference
                       -Wimplicit-fallthrough)
if(DFBWALL_WERROR)
  target_compile_options(dfbwall_warnings INTERFACE -Werror)
  # GCC 12 at -O3 (Release) reports std::string's own memcpy in `"literal" + std::string&&` as
  # overlapping (GCC bug 105329, a false positive inside libstdc++): a warning, not a failure.
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_GREATER_EQUAL 12
     AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
    target_compile_options(dfbwall_warnings INTERFACE -Wno-error=restrict)
  endif()
endif()

if(DFBWALL_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "DFBWALL_FUZZ needs clang (Debian 'clang'): -DCMAKE_CXX_COMPILER=clang++")
  endif()
  # Line tables are all a sanitizer's stack trace reads; full debug info costs ~30% more build.
  add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-omit-frame-pointer
                      -fno-sanitize-recover=all -g1)
  add_link_options(-fsanitize=address,undefined)
endif()

if(DFBWALL_SANITIZE)
  add_compile_options(-fsanitize=${DFBWALL_SANITIZE} -fno-omit-frame-pointer -fno-sanitize-recover=all
                      -g1)
  add_link_options(-fsanitize=${DFBWALL_SANITIZE})
endif()
