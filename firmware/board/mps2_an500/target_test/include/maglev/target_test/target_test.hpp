// maglev_target_test: a tiny heap-free test harness for on-target (M7 / QEMU)
// tests, printing CppUTest-style results:
//   OK (3 tests, 3 ran, 41 checks, 0 ignored, 0 filtered out)
//   Errors (1 failures, 3 tests, 3 ran, 40 checks, 0 ignored, 0 filtered out)
// run_all() returns the number of failed tests; the QEMU board's reset handler
// turns main()'s return value into QEMU's exit status.
//
// Writing a case (in any .cpp compiled INTO the image -- add it to the
// executable's sources or an OBJECT library; a case inside a STATIC library is
// dropped by the linker because nothing references it):
//
//   #include "maglev/target_test/target_test.hpp"
//   MAGLEV_TARGET_TEST(fixed_point, multiply_rounds_to_nearest) {
//     TT_CHECK(1 + 1 == 2);
//     TT_CHECK_EQUAL(0x40490fdbU, bits_of(3.14159265F));
//   }
//
// A failed check prints file:line and stops that test case (no exceptions:
// the macro returns from the test function).
#pragma once

#include <cstdint>

namespace maglev::target_test {

class Result {
 public:
  void count_check() { ++checks_; }
  void fail(const char* file, int line, const char* message);
  void fail_equal(const char* file, int line, const char* expression, std::uint64_t expected,
                  std::uint64_t actual);
  [[nodiscard]] bool failed() const { return failed_; }
  [[nodiscard]] std::uint32_t checks() const { return checks_; }

 private:
  std::uint32_t checks_ = 0;
  bool failed_ = false;
};

using TestFunction = void (*)(Result& result);

// One registered case. Instances are static objects (see MAGLEV_TARGET_TEST);
// their constructors link them into an intrusive list: no heap.
class TestCase {
 public:
  TestCase(const char* group, const char* name, TestFunction test_function);
  TestCase(const TestCase&) = delete;
  TestCase& operator=(const TestCase&) = delete;

  [[nodiscard]] const char* group() const { return group_; }
  [[nodiscard]] const char* name() const { return name_; }
  [[nodiscard]] TestFunction function() const { return function_; }
  [[nodiscard]] const TestCase* next() const { return next_; }

 private:
  const char* group_;
  const char* name_;
  TestFunction function_;
  TestCase* next_ = nullptr;
};

struct RunOptions {
  bool verbose = false;           // print "group.name" per case (CppUTest -v)
  const char* group_filter = nullptr;  // run only this group (CppUTest -g)
};

// Parses CppUTest-like options from a semihosting command line:
// "-v" verbose, "-g <group>" group filter. Unknown words are ignored (the
// first word is the kernel path). Stores pointers into `command_line`.
RunOptions parse_options(char* command_line);

// Runs every registered case (registration order), prints one '.' per passed
// case (or its name with -v), failure details, and the summary line.
// Returns the number of failed cases.
int run_all(const RunOptions& options);

// Number of registered cases (for self-checks).
int registered_count();

}  // namespace maglev::target_test

#define MAGLEV_TT_CONCAT_INNER(a, b) a##b
#define MAGLEV_TT_CONCAT(a, b) MAGLEV_TT_CONCAT_INNER(a, b)

#define MAGLEV_TARGET_TEST(group, name)                                                                \
  static void maglev_tt_##group##_##name(::maglev::target_test::Result& maglev_tt_result);            \
  static ::maglev::target_test::TestCase maglev_tt_case_##group##_##name{#group, #name,              \
                                                                          &maglev_tt_##group##_##name}; \
  static void maglev_tt_##group##_##name(::maglev::target_test::Result& maglev_tt_result)

#define TT_CHECK(condition)                                                       \
  do {                                                                            \
    maglev_tt_result.count_check();                                               \
    if (!(condition)) {                                                           \
      maglev_tt_result.fail(__FILE__, __LINE__, "CHECK(" #condition ") failed");  \
      return;                                                                     \
    }                                                                             \
  } while (0)

// Integer / bit-pattern equality; both sides are shown in hex on failure.
#define TT_CHECK_EQUAL(expected, actual)                                                   \
  do {                                                                                     \
    maglev_tt_result.count_check();                                                        \
    const auto maglev_tt_expected = (expected);                                            \
    const auto maglev_tt_actual = (actual);                                                \
    if (!(maglev_tt_expected == maglev_tt_actual)) {                                       \
      maglev_tt_result.fail_equal(__FILE__, __LINE__, "CHECK_EQUAL(" #expected ", " #actual ")", \
                                  static_cast<std::uint64_t>(maglev_tt_expected),          \
                                  static_cast<std::uint64_t>(maglev_tt_actual));           \
      return;                                                                              \
    }                                                                                      \
  } while (0)
