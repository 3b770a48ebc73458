#include "thermodrift/optim/box.hpp"

#include <gtest/gtest.h>

#include "thermodrift/error.hpp"

namespace thermodrift::optim {
namespace {

Box CSigmaBox() {
  return Box(Eigen::Vector3d(0.1, 1e-3, -1.0), Eigen::Vector3d(1e4, 100.0, 1.0), {true, true, false});
}

TEST(Box, LogScaleMapsUniformlyInLog10) {
  const Box box = CSigmaBox();
  const Eigen::VectorXd middle = box.FromUnit(Eigen::Vector3d(0.5, 0.5, 0.5));
  EXPECT_NEAR(middle[0], std::sqrt(0.1 * 1e4), 1e-9);  // geometric mean
  EXPECT_NEAR(middle[1], std::sqrt(1e-3 * 100.0), 1e-12);
  EXPECT_NEAR(middle[2], 0.0, 1e-15);
  EXPECT_NEAR(box.FromUnit(Eigen::Vector3d(0.2, 0.0, 0.0))[0], 1.0, 1e-12);  // 10^(-1 + 0.2·5)
}

TEST(Box, RoundTripsBetweenUnitCubeAndUserCoordinates) {
  const Box box = CSigmaBox();
  for (double u : {0.0, 0.013, 0.25, 0.5, 0.77, 0.999, 1.0}) {
    const Eigen::Vector3d unit(u, 1.0 - u, u * u);
    const Eigen::VectorXd back = box.ToUnit(box.FromUnit(unit));
    EXPECT_NEAR((back - unit).cwiseAbs().maxCoeff(), 0.0, 1e-12) << "u = " << u;
    const Eigen::Vector3d user(0.1 + u * 1e3, 1e-3 + u, -1.0 + u);
    EXPECT_NEAR(((box.FromUnit(box.ToUnit(user)) - user).array() / user.array().abs().max(1.0))
                    .abs().maxCoeff(), 0.0, 1e-12);
  }
}

TEST(Box, EndsMapExactlyToBoundsAndNothingLeavesTheBox) {
  const Box box = CSigmaBox();
  EXPECT_EQ(box.FromUnit(Eigen::Vector3d::Zero()), box.lower);
  EXPECT_EQ(box.FromUnit(Eigen::Vector3d::Ones()), box.upper);
  EXPECT_EQ(box.FromUnit(Eigen::Vector3d(-3.0, 2.0, 7.0)), Eigen::Vector3d(0.1, 100.0, 1.0));
  for (int k = 0; k <= 1000; ++k) {
    const double u = k / 1000.0;
    EXPECT_TRUE(box.Contains(box.FromUnit(Eigen::Vector3d(u, u, u)))) << u;
  }
}

TEST(Box, FixedDimensionMapsToItsValue) {
  const Box box(Eigen::Vector2d(2.0, 0.0), Eigen::Vector2d(2.0, 1.0));
  EXPECT_TRUE(box.IsValid(nullptr));
  EXPECT_EQ(box.FromUnit(Eigen::Vector2d(0.7, 0.5))[0], 2.0);
  EXPECT_EQ(box.ToUnit(Eigen::Vector2d(2.0, 0.5))[0], 0.0);
}

TEST(Box, IsValidRejectsBadBoxes) {
  std::string why;
  EXPECT_FALSE(Box(Eigen::Vector2d(1.0, 0.0), Eigen::Vector2d(0.0, 1.0)).IsValid(&why));
  EXPECT_NE(why.find("lower"), std::string::npos);
  EXPECT_FALSE(Box(Eigen::Vector2d(0.0, 0.0), Eigen::Vector3d(1.0, 1.0, 1.0)).IsValid(&why));
  EXPECT_FALSE(Box(Eigen::Vector2d(0.0, 1.0), Eigen::Vector2d(1.0, 2.0), {true, false}).IsValid(&why));
  EXPECT_NE(why.find("log-scale"), std::string::npos);
  EXPECT_FALSE(Box(Eigen::Vector2d(0.1, 1.0), Eigen::Vector2d(1.0, 2.0), {true}).IsValid(&why));
  EXPECT_FALSE(Box(Eigen::Vector2d(0.0, -INFINITY), Eigen::Vector2d(1.0, 2.0)).IsValid(&why));
  EXPECT_FALSE(Box().IsValid(&why));
  EXPECT_THROW(Box().validate(), UsageError);
}

}  // namespace
}  // namespace thermodrift::optim
