#include <gtest/gtest.h>

#include <cmath>

#include "granuflow/errors.hpp"
#include "granuflow/input.hpp"
#include "granuflow/quantity.hpp"

namespace granuflow {

TEST(Quantity, ConvertsEdgeUnitsToSi) {
  EXPECT_DOUBLE_EQ(to_si(60, "degC", "K", "x"), 333.15);
  EXPECT_DOUBLE_EQ(to_si(700, "m3/h", "m3/s", "x"), 700.0 / 3600.0);
  EXPECT_DOUBLE_EQ(to_si(90, "g/min", "kg/s", "x"), 1.5e-3);
  EXPECT_DOUBLE_EQ(to_si(200, "um", "m", "x"), 2e-4);
  EXPECT_DOUBLE_EQ(to_si(5, "g/kg", "kg/kg", "x"), 5e-3);
  EXPECT_THROW(to_si(1, "degC", "kg/s", "bed.T"), ConfigError);
  EXPECT_DOUBLE_EQ(to_si(2, "inch", "m", "bed.d"), 0.0508);  // composed from the units library, not a list
  EXPECT_THROW(to_si(1, "furlong", "kg", "bed.m"), ConfigError);
  EXPECT_THROW(to_si(1, "blorp", "m", "bed.d"), ConfigError);
  double v;
  std::string u;
  ASSERT_TRUE(parse_quantity("700 m3/h", &v, &u));
  EXPECT_EQ(v, 700);
  EXPECT_EQ(u, "m3/h");
  ASSERT_TRUE(parse_quantity("-1.5e-3", &v, &u));
  EXPECT_EQ(u, "");
  EXPECT_FALSE(parse_quantity("abc", &v, &u));
}

// Parameters, states and outputs declare coherent SI units: understood, without a scale or an origin.
TEST(Quantity, DeclaredUnitsAreCoherentSi) {
  for (const char* si : {"K", "kg/s", "J/(kg K)", "W/(m2 K)", "W/K", "Pa s", "1/s", "-", "kg/kg", "m2/s", "1/m3"})
    EXPECT_TRUE(is_known_si_unit(si)) << si;
  for (const char* not_si : {"kW", "degC", "%", "g", "h", "um", "blorp", ""})
    EXPECT_FALSE(is_known_si_unit(not_si)) << not_si;
}

TEST(PiecewiseLinear, InterpolatesAndIntegratesExactly) {
  PiecewiseLinear f({0, 10, 30}, {1, 3, -1}, PiecewiseLinear::Interp::kLinear, "f");
  EXPECT_DOUBLE_EQ(f(5), 2.0);
  EXPECT_DOUBLE_EQ(f(20), 1.0);
  EXPECT_DOUBLE_EQ(f(100), -1.0);
  // trapezoids: 0..10 -> 20, 10..30 -> 20
  EXPECT_DOUBLE_EQ(f.integral(0, 30), 40.0);
  EXPECT_DOUBLE_EQ(f.integral(5, 20), 0.5 * (2 + 3) * 5 + 0.5 * (3 + 1) * 10);
  PiecewiseLinear s({0, 10}, {1, 5}, PiecewiseLinear::Interp::kStep, "s");
  EXPECT_DOUBLE_EQ(s(9.999), 1.0);
  EXPECT_DOUBLE_EQ(s(10), 5.0);
  EXPECT_DOUBLE_EQ(s.integral(0, 20), 10 + 50);
  EXPECT_THROW(PiecewiseLinear({0, 0}, {1, 2}, PiecewiseLinear::Interp::kLinear, "bad"), ConfigError);
}

}  // namespace granuflow
