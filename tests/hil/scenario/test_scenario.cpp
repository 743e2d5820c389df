// Project and STL headers first: CppUTest redefines `new` for leak detection.
#include "maglev/scenario/scenario.hpp"

#include <CppUTest/TestHarness.h>

using namespace maglev::scenario;

TEST_GROUP(Scenario){};

TEST(Scenario, ParsesAllSectionsAndSortsTimeline) {
  const auto r = parse_scenario(R"(# an example
[scenario]
name = x_steps
duration_s = 3.5   # seconds
kernel = float32
[plant]
payload_kg = 0.5396
[controller]
x.kp = 36000
[timeline]
2.5 step x 8e-6
0.0 levitate
1.5 step x -4e-6
[metrics]
step x 2.5 3.3 x_step2
[paper]
x_step2_overshoot_percent = 3.25
)",
                                "mem");
  CHECK_TRUE(r.ok());
  const Scenario& s = *r.scenario;
  STRCMP_EQUAL("x_steps", s.name().c_str());
  DOUBLES_EQUAL(3.5, s.duration_s(), 0);
  STRCMP_EQUAL("0.5396", s.plant.at("payload_kg").c_str());
  STRCMP_EQUAL("36000", s.controller.at("x.kp").c_str());
  LONGS_EQUAL(3, s.timeline.size());
  STRCMP_EQUAL("levitate", s.timeline[0].verb.c_str());
  DOUBLES_EQUAL(1.5, s.timeline[1].t_s, 0);
  STRCMP_EQUAL("-4e-6", s.timeline[1].args[1].c_str());
  LONGS_EQUAL(13, s.timeline[1].line);
  LONGS_EQUAL(1, s.metrics.size());
  STRCMP_EQUAL("step", s.metrics[0].kind.c_str());
  DOUBLES_EQUAL(3.25, s.paper.at("x_step2_overshoot_percent"), 0);
}

TEST(Scenario, ReportsEveryErrorWithItsLine) {
  const auto r = parse_scenario(R"([scenario]
name = bad
duration_s = 1
[timeline]
abc levitate
5.0 land
[bogus]
[plant]
gap
[paper]
x = not_a_number
)",
                                "bad.scenario");
  CHECK_FALSE(r.ok());
  CHECK_FALSE(r.scenario.has_value());
  LONGS_EQUAL(5, r.errors.size());
  LONGS_EQUAL(5, r.errors[0].line);   // abc is not a time
  LONGS_EQUAL(7, r.errors[1].line);   // unknown section
  LONGS_EQUAL(9, r.errors[2].line);   // no '='
  LONGS_EQUAL(11, r.errors[3].line);  // paper value not a number
  LONGS_EQUAL(6, r.errors[4].line);   // 5.0 s after duration
  STRCMP_CONTAINS("bad.scenario:5:", r.errors[0].to_string().c_str());
}

TEST(Scenario, RequiresNameAndPositiveDuration) {
  const auto r = parse_scenario("[scenario]\nduration_s = -1\n", "x");
  CHECK_FALSE(r.ok());
  LONGS_EQUAL(2, r.errors.size());
}

TEST(Scenario, StrictNumbers) {
  CHECK_TRUE(parse_number("1e-9").has_value());
  CHECK_FALSE(parse_number("1e-9x").has_value());
  CHECK_FALSE(parse_number("nan").has_value());
  CHECK_FALSE(parse_number("").has_value());
}

TEST(Scenario, MissingFileIsAnError) {
  const auto r = load_scenario_file("/nonexistent/x.scenario");
  CHECK_FALSE(r.ok());
  STRCMP_CONTAINS("cannot open", r.errors[0].message.c_str());
}

// Found by fuzz_scenario: a [timeline] or [metrics] line of only vertical
// tab / form feed trimmed to non-empty but split into no token, and the
// parser read the first token of an empty list (UBSan: vector index out of
// range). Such a line is blank now, like one of spaces.
TEST(Scenario, LinesOfOtherWhitespaceAreBlank) {
  const auto r = parse_scenario("[scenario]\nname = ws\nduration_s = 1\n[timeline]\n\v\n0.5 levitate\f\n[metrics]\n\f \v\n",
                                "mem");
  CHECK_TRUE(r.ok());
  LONGS_EQUAL(1, r.scenario->timeline.size());
  STRCMP_EQUAL("levitate", r.scenario->timeline[0].verb.c_str());
  LONGS_EQUAL(0, r.scenario->metrics.size());
}
