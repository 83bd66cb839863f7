// WALKVIS_DCHECK(condition): the contracts a header states with "must", checked where they are
// relied on. On in Debug and sanitizer builds (WALKVIS_DCHECKS defined, see CMakeLists.txt), where
// a broken contract aborts with the file, line and condition; compiled out of Release builds,
// where the condition is not evaluated (so it must have no side effect).
#pragma once

#if defined(WALKVIS_DCHECKS)
#include <cstdio>
#include <cstdlib>
#define WALKVIS_DCHECK(condition)                                                              \
  do {                                                                                         \
    if (!(condition)) {                                                                        \
      std::fprintf(stderr, "%s:%d: walkvis contract broken: %s\n", __FILE__, __LINE__, #condition); \
      std::abort();                                                                            \
    }                                                                                          \
  } while (false)
#else
#define WALKVIS_DCHECK(condition) \
  do {                            \
    if (false && (condition)) {   \
    }                             \
  } while (false)
#endif
