#include "maglev/target_test/target_test.hpp"

#include <cstring>

#include "maglev/board/mps2_an500/semihosting.hpp"

namespace maglev::target_test {
namespace {

namespace hw = maglev::board::mps2_an500;

// Intrusive list in registration order. Zero-initialised (.bss) before any
// constructor runs, so registration order between files does not matter.
TestCase* g_first = nullptr;
TestCase* g_last = nullptr;
int g_count = 0;

void print_location(const char* file, int line) {
  hw::semihost_write("\n");
  hw::semihost_write(file);
  hw::semihost_write(":");
  hw::semihost_write_signed(line);
  hw::semihost_write(": error: ");
}

}  // namespace

void Result::fail(const char* file, int line, const char* message) {
  failed_ = true;
  print_location(file, line);
  hw::semihost_write(message);
  hw::semihost_write("\n");
}

void Result::fail_equal(const char* file, int line, const char* expression, std::uint64_t expected,
                        std::uint64_t actual) {
  failed_ = true;
  print_location(file, line);
  hw::semihost_write(expression);
  hw::semihost_write(" failed\n\texpected <");
  hw::semihost_write_hex(expected, 16);
  hw::semihost_write(">\n\tbut was  <");
  hw::semihost_write_hex(actual, 16);
  hw::semihost_write(">\n");
}

TestCase::TestCase(const char* group, const char* name, TestFunction test_function)
    : group_(group), name_(name), function_(test_function) {
  if (g_last == nullptr) {
    g_first = this;
  } else {
    g_last->next_ = this;
  }
  g_last = this;
  ++g_count;
}

int registered_count() { return g_count; }

RunOptions parse_options(char* command_line) {
  RunOptions options;
  char* cursor = command_line;
  bool expect_group = false;
  while (cursor != nullptr && *cursor != '\0') {
    while (*cursor == ' ') {
      ++cursor;
    }
    if (*cursor == '\0') {
      break;
    }
    char* word = cursor;
    while (*cursor != '\0' && *cursor != ' ') {
      ++cursor;
    }
    if (*cursor == ' ') {
      *cursor = '\0';
      ++cursor;
    }
    if (expect_group) {
      options.group_filter = word;
      expect_group = false;
    } else if (std::strcmp(word, "-v") == 0) {
      options.verbose = true;
    } else if (std::strcmp(word, "-g") == 0) {
      expect_group = true;
    }
  }
  return options;
}

int run_all(const RunOptions& options) {
  int ran = 0;
  int failures = 0;
  int filtered = 0;
  std::uint32_t checks = 0;
  for (const TestCase* test = g_first; test != nullptr; test = test->next()) {
    if (options.group_filter != nullptr && std::strcmp(options.group_filter, test->group()) != 0) {
      ++filtered;
      continue;
    }
    if (options.verbose) {
      hw::semihost_write("TEST(");
      hw::semihost_write(test->group());
      hw::semihost_write(", ");
      hw::semihost_write(test->name());
      hw::semihost_write(")");
    }
    Result result;
    test->function()(result);
    ++ran;
    checks += result.checks();
    if (result.failed()) {
      ++failures;
      hw::semihost_write("\tin TEST(");
      hw::semihost_write(test->group());
      hw::semihost_write(", ");
      hw::semihost_write(test->name());
      hw::semihost_write(")\n");
    } else if (options.verbose) {
      hw::semihost_write(" - ok\n");
    } else {
      hw::semihost_write(".");
    }
  }
  hw::semihost_write("\n");
  if (failures == 0) {
    hw::semihost_write("OK (");
  } else {
    hw::semihost_write("Errors (");
    hw::semihost_write_signed(failures);
    hw::semihost_write(" failures, ");
  }
  hw::semihost_write_signed(g_count);
  hw::semihost_write(" tests, ");
  hw::semihost_write_signed(ran);
  hw::semihost_write(" ran, ");
  hw::semihost_write_unsigned(checks);
  hw::semihost_write(" checks, 0 ignored, ");
  hw::semihost_write_signed(filtered);
  hw::semihost_write(" filtered out)\n\n");
  return failures;
}

}  // namespace maglev::target_test
