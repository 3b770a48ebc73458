// The workplace's shared test data (tests/CMakeLists.txt: THERMODRIFT_SHARED_DATA).
#pragma once

#include <filesystem>
#include <string>

#include <gtest/gtest.h>

namespace thermodrift::testing {

// The path of `relative` in the shared data folder.
inline std::string shared_data(const std::string& relative) {
  return std::string(THERMODRIFT_SHARED_DATA) + "/" + relative;
}

}  // namespace thermodrift::testing

// Skips the test, naming the folder, when the shared data is not where the build looks
// for it (a clone without the workplace's folder beside it).
#define THERMODRIFT_SKIP_WITHOUT_SHARED_DATA(relative)                                                        \
  do {                                                                                                        \
    if (!std::filesystem::exists(::thermodrift::testing::shared_data(relative))) {                            \
      GTEST_SKIP() << ::thermodrift::testing::shared_data(relative)                                           \
                   << " is absent: configure with -DTHERMODRIFT_SHARED_DATA=DIR to run this test";            \
    }                                                                                                         \
  } while (false)
