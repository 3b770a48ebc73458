// The training envelope: built from the ready samples of a feature table, and the one
// test of a sample against it, margins included.
#include "thermodrift/features/envelope.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "thermodrift/error.hpp"

namespace thermodrift {
namespace {

FeatureTable table_of(const std::vector<double>& temperature, const std::vector<double>& rate) {
  FeatureTable table;
  table.temperature = temperature;
  table.rate = rate;
  const auto n = static_cast<Eigen::Index>(temperature.size());
  table.features.resize(n, 2);
  for (Eigen::Index i = 0; i < n; ++i) {
    table.features(i, 0) = temperature[static_cast<std::size_t>(i)] - 20;
    table.features(i, 1) = rate[static_cast<std::size_t>(i)];
    table.row.push_back(static_cast<std::size_t>(i));
  }
  return table;
}

TEST(TrainingEnvelope, RangesAndDirectionsOfTheTable) {
  // A heating-only log: the largest cooling rate (-0.1) stays under 0.2 °C/min.
  const auto envelope = TrainingEnvelope::of(table_of({20, 35, 60, 59}, {0.0, 1.0, 0.3, -0.1}));
  EXPECT_EQ(envelope.temperature, (Range{20, 60}));
  EXPECT_EQ(envelope.rate, (Range{-0.1, 1.0}));
  EXPECT_TRUE(envelope.heating_seen);
  EXPECT_FALSE(envelope.cooling_seen);
  ASSERT_EQ(envelope.terms.size(), 2u);
  EXPECT_EQ(envelope.terms[0], (Range{0, 40}));
  EXPECT_EQ(envelope.terms[1], (Range{-0.1, 1.0}));
  EXPECT_THROW(TrainingEnvelope::of(FeatureTable{}), UsageError);
}

TEST(TrainingEnvelope, MarginsAreTheLargerOfAFractionAndAMinimum) {
  TrainingEnvelope wide;  // 100 °C range: 2 % = 2 °C; 2 °C/min range: 10 % = 0.2 °C/min
  wide.temperature = {-40, 60};
  wide.rate = {-1, 1};
  wide.heating_seen = wide.cooling_seen = true;
  EXPECT_EQ(wide.temperature_limits(), (Range{-42, 62}));
  EXPECT_NEAR(wide.rate_limits().max, 1.2, 1e-12);
  EXPECT_FALSE(wide.check(61.9, 0).any());
  EXPECT_TRUE(wide.check(62.1, 0).temperature_high);
  EXPECT_TRUE(wide.check(-42.1, 0).temperature_low);
  EXPECT_TRUE(wide.check(20, 1.25).rate_high);
  EXPECT_FALSE(wide.check(20, -1.15).any());

  TrainingEnvelope narrow;  // 10 °C range: the 1 °C minimum; 0.1 °C/min range: the 0.05 minimum
  narrow.temperature = {20, 30};
  narrow.rate = {-0.05, 0.05};
  EXPECT_EQ(narrow.temperature_limits(), (Range{19, 31}));
  EXPECT_NEAR(narrow.rate_limits().min, -0.1, 1e-12);
  EXPECT_FALSE(narrow.check(30.9, 0.09).any());
}

TEST(TrainingEnvelope, AnUnseenDirectionIsOutsideAndWarnedOf) {
  const auto heating_only = TrainingEnvelope::of(table_of({20, 60}, {0.0, 1.0}));
  const Excursion cooling = heating_only.check(40, -0.5);
  EXPECT_TRUE(cooling.cooling_unseen);
  EXPECT_FALSE(cooling.heating_unseen);
  EXPECT_FALSE(heating_only.check(40, -0.15).direction());  // a soak's wander is not cooling
  const auto warnings = heating_only.coverage_warnings();
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("never seen cooling"), std::string::npos) << warnings[0];

  const auto soak = TrainingEnvelope::of(table_of({20, 20.5}, {-0.1, 0.1}));
  ASSERT_EQ(soak.coverage_warnings().size(), 1u);
  EXPECT_NE(soak.coverage_warnings()[0].find("soak-only"), std::string::npos);
  EXPECT_TRUE(TrainingEnvelope::of(table_of({-40, 60}, {-1, 1})).coverage_warnings().empty());
}

TEST(EnvelopeTally, CountsByLimitAndNamesTheLimitsCrossed) {
  const auto envelope = TrainingEnvelope::of(table_of({20, 60}, {0.0, 1.0}));
  const EnvelopeTally tally = tally_outside(envelope, table_of({30, 70, 40, 50}, {0.5, 0.5, -0.5, 0.0}));
  EXPECT_EQ(tally.samples, 4u);
  EXPECT_EQ(tally.outside, 2u);
  EXPECT_EQ(tally.temperature_high, 1u);
  EXPECT_EQ(tally.cooling_unseen, 1u);
  EXPECT_EQ(tally.rate_low, 1u);  // -0.5 is below -0.1
  EXPECT_DOUBLE_EQ(tally.outside_fraction(), 0.5);
  EXPECT_EQ(tally.describe(envelope), "temperature above 61.0 °C, rate below -0.10 °C/min, cooling never seen in training");
}

}  // namespace
}  // namespace thermodrift
