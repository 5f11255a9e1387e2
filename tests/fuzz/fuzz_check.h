// What the fuzz targets share. A parser may reject any input, with its own error type
// naming the problem; anything else it does is a bug: a crash, a sanitizer report, an
// exception of another type (it escapes the target and aborts), or an accepted input that
// breaks a promise of the parser's API, which fuzz_require reports and aborts on.
#pragma once

#include <cstdio>
#include <cstdlib>

#define fuzz_require(condition)                                                                      \
    do {                                                                                            \
        if (!(condition)) {                                                                         \
            std::fprintf(stderr, "%s:%d: accepted input breaks: %s\n", __FILE__, __LINE__, #condition); \
            std::abort();                                                                           \
        }                                                                                           \
    } while (0)
