// dps — the tests' own tiny check header (no framework). Each check prints file:line and the
// values on failure and counts it; a test's main returns dps_test::Report().
#pragma once

#include <cmath>
#include <cstdio>
#include <iostream>
#include <string>

namespace dps_test {

inline int& Failures() {
  static int failures = 0;
  return failures;
}
inline int& Checks() {
  static int checks = 0;
  return checks;
}

// Prints a summary line and returns the exit code for main: failure when a check failed or when
// no check ran at all (a test that checks nothing proves nothing).
inline int Report() {
  std::cout << Checks() - Failures() << " passed, " << Failures() << " failed" << std::endl;
  if (Checks() == 0) {
    std::cerr << "no check ran" << std::endl;
    return 1;
  }
  return Failures() == 0 ? 0 : 1;
}

}  // namespace dps_test

#define CHECK(cond)                                                                   \
  do {                                                                                \
    ++dps_test::Checks();                                                             \
    if (!(cond)) {                                                                    \
      ++dps_test::Failures();                                                         \
      std::cerr << __FILE__ << ":" << __LINE__ << ": CHECK(" #cond ") failed" << std::endl; \
    }                                                                                 \
  } while (0)

#define CHECK_EQ(a, b)                                                                     \
  do {                                                                                     \
    ++dps_test::Checks();                                                                  \
    const auto& va_ = (a);                                                                 \
    const auto& vb_ = (b);                                                                 \
    if (!(va_ == vb_)) {                                                                   \
      ++dps_test::Failures();                                                              \
      std::cerr << __FILE__ << ":" << __LINE__ << ": CHECK_EQ(" #a ", " #b ") failed: " << va_ \
                << " != " << vb_ << std::endl;                                             \
    }                                                                                      \
  } while (0)

#define CHECK_NEAR(a, b, tol)                                                                \
  do {                                                                                       \
    ++dps_test::Checks();                                                                    \
    const double va_ = (a);                                                                  \
    const double vb_ = (b);                                                                  \
    if (!(std::abs(va_ - vb_) <= (tol))) {                                                   \
      ++dps_test::Failures();                                                                \
      std::cerr.precision(12);                                                               \
      std::cerr << __FILE__ << ":" << __LINE__ << ": CHECK_NEAR(" #a ", " #b ", " #tol        \
                << ") failed: " << va_ << " vs " << vb_ << " (|diff| = " << std::abs(va_ - vb_) \
                << ")" << std::endl;                                                         \
    }                                                                                        \
  } while (0)

// Checks that `expr` throws an exception of type `type`, and, when `needle` is non-empty, that its
// message contains `needle`.
#define CHECK_THROWS_WITH(expr, type, needle)                                                  \
  do {                                                                                         \
    ++dps_test::Checks();                                                                      \
    bool thrown_ = false;                                                                      \
    std::string message_;                                                                      \
    try {                                                                                      \
      (void)(expr);                                                                            \
    } catch (const type& e_) {                                                                \
      thrown_ = true;                                                                          \
      message_ = e_.what();                                                                    \
    } catch (...) {                                                                            \
    }                                                                                          \
    const std::string needle_ = (needle);                                                      \
    if (!thrown_ || message_.find(needle_) == std::string::npos) {                             \
      ++dps_test::Failures();                                                                  \
      std::cerr << __FILE__ << ":" << __LINE__ << ": CHECK_THROWS(" #expr ", " #type ") failed: " \
                << (thrown_ ? "message '" + message_ + "' lacks '" + needle_ + "'"             \
                            : std::string("nothing (or another type) thrown"))                 \
                << std::endl;                                                                  \
    }                                                                                          \
  } while (0)

#define CHECK_THROWS(expr, type) CHECK_THROWS_WITH(expr, type, "")
