// With STRATA_PROFILING = 0 the scope macro compiles to nothing: no timer object, no recorded sample.
// The build defines STRATA_PROFILING=1 for everything; this file redefines it before the first include.
#undef STRATA_PROFILING
#define STRATA_PROFILING 0
#include "profiling/profiler.h"

#include <gtest/gtest.h>

#include <type_traits>

namespace strata {
namespace {

TEST(ProfilerCompiledOut, ScopeMacroRecordsNothing) {
  Profiler profiler(8);
  profiler.begin_frame();
  {
    STRATA_PROFILE_SCOPE(profiler, "fk");
    STRATA_PROFILE_SCOPE(profiler, "skin");
  }
  profiler.end_frame();
  EXPECT_TRUE(profiler.stats().empty());
  EXPECT_TRUE(profiler.events().empty());
  EXPECT_TRUE(profiler.names().empty()) << "not even the name is interned";
}

// The macro is an expression statement of type void, usable anywhere a statement is.
static_assert(std::is_void_v<decltype(STRATA_PROFILE_SCOPE(std::declval<Profiler&>(), "x"))>);

}  // namespace
}  // namespace strata
