#pragma once
// Assertions for invariants, in two strengths:
//   CANDELA_CHECK(cond, message)   always evaluated; on failure throws Error(Internal) naming the
//                                  source file, line, condition and message. For invariants whose
//                                  failure would read or write out of bounds even in a release
//                                  build (an index from another stage, a size from a file).
//   CANDELA_DCHECK(cond, message)  evaluated in debug builds only (NDEBUG unset), compiled out
//                                  in release builds: for invariants in hot loops that the code
//                                  around them already guarantees, checked where tests run with
//                                  a debug or sanitizer build.
// The message is any expression convertible to std::string; it is built only on failure.
// Named CANDELA_* so they never collide with Catch2's CHECK in tests.
#include "candela/util/error.h"

#include <string>

namespace candela::detail {

[[noreturn]] void check_failed(const char* file, int line, const char* condition,
                               const std::string& message);

} // namespace candela::detail

#define CANDELA_CHECK(cond, message)                                                               \
    do {                                                                                           \
        if (__builtin_expect(!(cond), 0))                                                          \
            ::candela::detail::check_failed(__FILE__, __LINE__, #cond, (message));                 \
    } while (false)

#ifdef NDEBUG
#define CANDELA_DCHECK(cond, message)                                                              \
    do {                                                                                           \
        (void)sizeof(cond);                                                                        \
    } while (false)
#else
#define CANDELA_DCHECK(cond, message) CANDELA_CHECK(cond, message)
#endif
