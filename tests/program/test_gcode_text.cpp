// The one emitter's numbers (program/gcode_text.hpp): written with std::to_chars, they must
// be what printf's %.3f and %.5f write, byte for byte, or every file would change.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "program/gcode_text.hpp"

namespace nonplanar {
namespace {

std::string printf_move(double x, double y, double z, double e) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "G1 X%.3f Y%.3f Z%.3f E%.5f\n", x, y, z, e);
  return buf;
}

std::string written(double x, double y, double z, double e) {
  program::GcodeText w(true);
  ProgramMove m;
  m.to = {x, y, z};
  m.xy = m.z = true;
  m.de = e;
  w.move(m);
  EXPECT_FALSE(w.fault);
  return w.out;
}

TEST(GcodeText, NumbersAreWhatPrintfWrites) {
  // Ties and near-ties of the last digit, negative zero and tiny negatives ("-0.000"), large
  // values.
  for (const double v :
       {0.0, -0.0, 0.0005, 0.0015, 0.0025, 1.0005, 2.5e-4, -2.5e-4, 1e-7, -1e-7, -0.0004999,
        123.4565, 219.9995, -5.0005, 1e6 + 0.0005, 99999.999995, 0.000005, 0.000015, -0.000005})
    EXPECT_EQ(written(v, -v, v * 0.5, v), printf_move(v, -v, v * 0.5, v)) << v;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> pos(-300, 300), e(-10, 1e5);
  for (int k = 0; k < 20000; ++k) {
    const double x = pos(rng), y = pos(rng), z = pos(rng) / 10, de = e(rng);
    ASSERT_EQ(written(x, y, z, de), printf_move(x, y, z, de)) << x << " " << y << " " << de;
  }
  // Near the ties of the last digit, where the integers' fast path must step aside: k
  // thousandths plus half of one, give or take a few units in the last place.
  std::uniform_int_distribution<int> thousandths(-300000, 300000), ulps(-4, 4);
  for (int k = 0; k < 200000; ++k) {
    double v = (thousandths(rng) + 0.5) / 1000;
    for (int u = ulps(rng); u != 0; u += u > 0 ? -1 : 1) v = std::nextafter(v, u > 0 ? 1e9 : -1e9);
    const double e5 = v / 100;  // ties of the fifth decimal
    ASSERT_EQ(written(v, v, v, e5), printf_move(v, v, v, e5)) << v;
  }
  // Past the fast path's range (10^9 units of the last digit) and non-finite.
  for (const double v : {1e6 + 0.0004, 1e7 + 0.25, -4e6 - 0.0006, 12345.678905, -9999.999995})
    EXPECT_EQ(written(v, v, v, v), printf_move(v, v, v, v)) << v;
}

}  // namespace
}  // namespace nonplanar
