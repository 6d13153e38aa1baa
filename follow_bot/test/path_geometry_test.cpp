#include "follow_bot/path_geometry.h"

#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <vector>

namespace follow_bot {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Points every centimetre along the line through (0, offset) at `heading`, s from `begin` to
// `end`, stamped in the order a robot driving along +heading sees them (or the reverse).
void straightPath(double offset, double heading, double begin, double end, bool reverse,
                  std::vector<cv::Point2d>& positions, std::vector<double>& stamps) {
  for (double s = begin; s <= end + 1e-9; s += 0.01) {
    positions.emplace_back(s * std::cos(heading), offset + s * std::sin(heading));
    stamps.push_back(reverse ? -s : s);
  }
}

TEST(PathGeometry, FitsAStraightPathExactlyAndItsDirectionByTheStamps) {
  const double heading = 10.0 * kPi / 180.0;
  std::vector<cv::Point2d> positions;
  std::vector<double> stamps;
  straightPath(0.1, heading, -0.2, 0.3, false, positions, stamps);
  std::optional<PathAtBase> path = fitPathAtBase(positions, stamps, 0.4, 0.1);
  ASSERT_TRUE(path);
  EXPECT_NEAR(path->lateral, 0.1 * std::cos(heading), 1e-9);  // the base's distance to the line
  EXPECT_NEAR(path->heading, heading, 1e-9);
  EXPECT_NEAR(path->curvature, 0.0, 1e-9);

  // The same points seen in the other order: the path runs the other way, the line on its right.
  stamps.clear();
  positions.clear();
  straightPath(0.1, heading, -0.2, 0.3, true, positions, stamps);
  path = fitPathAtBase(positions, stamps, 0.4, 0.1);
  ASSERT_TRUE(path);
  EXPECT_NEAR(path->lateral, -0.1 * std::cos(heading), 1e-9);
  EXPECT_NEAR(std::remainder(path->heading - heading - kPi, 2 * kPi), 0.0, 1e-9);
}

TEST(PathGeometry, FitsAnArcsOffsetHeadingAndCurvature) {
  // A left-hand arc of radius 0.6 m passing 5 cm to the left of the base, heading along x there.
  const double radius = 0.6;
  const cv::Point2d centre(0.0, 0.05 + radius);
  std::vector<cv::Point2d> positions;
  std::vector<double> stamps;
  for (double s = -0.25; s <= 0.25 + 1e-9; s += 0.01) {
    const double angle = s / radius;
    positions.push_back(centre + radius * cv::Point2d(std::sin(angle), -std::cos(angle)));
    stamps.push_back(s);
  }
  const std::optional<PathAtBase> path = fitPathAtBase(positions, stamps, 0.4, 0.1);
  ASSERT_TRUE(path);
  EXPECT_NEAR(path->lateral, 0.05, 2e-4);
  EXPECT_NEAR(path->heading, 0.0, 2e-3);
  // A parabola on a circle: a few per cent off 1/R over a window two thirds of the radius.
  EXPECT_NEAR(path->window_curvature, 1.0 / radius, 0.05 / radius);
}

TEST(PathGeometry, RefusesTooFewPointsAndABaseFarBeyondThem) {
  std::vector<cv::Point2d> positions{{0.0, 0.0}, {0.01, 0.0}};
  std::vector<double> stamps{0.0, 1.0};
  EXPECT_FALSE(fitPathAtBase(positions, stamps, 0.4, 0.1));  // two points
  positions.clear();
  stamps.clear();
  straightPath(0.0, 0.0, 0.5, 0.9, false, positions, stamps);  // starts 0.5 m ahead
  EXPECT_FALSE(fitPathAtBase(positions, stamps, 0.4, 0.1));
  EXPECT_TRUE(fitPathAtBase(positions, stamps, 0.4, 0.6));
}

TEST(PathGeometry, PursuesTheArcThroughThePointAtTheLookAhead) {
  // Every point of a circle tangent to the heading at the base lies on the pursuit arc.
  const double radius = 0.8;
  std::vector<cv::Point2d> positions;
  for (double angle = 0.05; angle < 1.0; angle += 0.05) {
    positions.emplace_back(radius * std::sin(angle), radius * (1.0 - std::cos(angle)));
  }
  const std::optional<double> curvature = pursuitCurvature(positions, 0.3);
  ASSERT_TRUE(curvature);
  EXPECT_NEAR(*curvature, 1.0 / radius, 1e-12);
  EXPECT_FALSE(pursuitCurvature({{-0.2, 0.1}, {0.0, 0.3}}, 0.3));  // nothing ahead
}

TEST(PathGeometry, WalksArcsExactly) {
  const double radius = 0.5;
  const auto [end, tangent] = alongArc({1.0, 2.0}, {1.0, 0.0}, 1.0 / radius, 0.5 * kPi * radius);
  EXPECT_NEAR(end.x, 1.0 + radius, 1e-12);
  EXPECT_NEAR(end.y, 2.0 + radius, 1e-12);
  EXPECT_NEAR(tangent.x, 0.0, 1e-12);
  EXPECT_NEAR(tangent.y, 1.0, 1e-12);
  const cv::Point2d quarter = arcDisplacement(0.5 * kPi * radius, 0.5 * kPi);
  EXPECT_NEAR(quarter.x, radius, 1e-12);
  EXPECT_NEAR(quarter.y, radius, 1e-12);
  // Nearly straight: the series, not 0/0.
  const cv::Point2d straight = arcDisplacement(2.0, 1e-9);
  EXPECT_NEAR(straight.x, 2.0, 1e-15);
  EXPECT_NEAR(straight.y, 1e-9, 1e-20);
}

TEST(PathGeometry, SamplesAnArcEveryCentimetreWithItsStamps) {
  std::vector<cv::Point2d> positions;
  std::vector<double> stamps;
  sampleArc({0.0, 0.0}, {1.0, 0.0}, 2.0, 0.255, 10.0, 4.0, positions, stamps);
  ASSERT_EQ(positions.size(), 26u);  // ceil(25.5 cm / 1 cm), `from` itself left out
  const cv::Point2d centre(0.0, 0.5);
  for (size_t i = 0; i < positions.size(); ++i) {
    const cv::Point2d d = positions[i] - centre;
    EXPECT_NEAR(std::sqrt(d.dot(d)), 0.5, 1e-12) << i;
  }
  EXPECT_NEAR(stamps.back(), 10.0 + 4.0 * 0.255, 1e-12);
  EXPECT_NEAR(stamps.front(), 10.0 + 4.0 * 0.255 / 26, 1e-12);
}

TEST(PathGeometry, BridgesAStraightIntoAQuarterTurn) {
  // A straight along x that the camera lost, seen again at (1, 0.5) heading along y: the
  // straight goes on for 0.5 m, then a quarter circle of 0.5 m about (0.5, 0.5) ends there.
  std::vector<cv::Point2d> positions;
  std::vector<double> stamps;
  sampleBridge({0.0, 0.0}, PathDirection{{1.0, 0.0}, 0.0}, 0.0, {1.0, 0.5}, cv::Point2d(0.0, 1.0),
               1.0, positions, stamps);
  ASSERT_FALSE(positions.empty());
  EXPECT_NEAR(positions.back().x, 1.0, 1e-9);
  EXPECT_NEAR(positions.back().y, 0.5, 1e-9);
  EXPECT_NEAR(stamps.back(), 1.0, 1e-9);
  for (const cv::Point2d& p : positions) {
    if (p.x <= 0.5 - 1e-6) {
      EXPECT_NEAR(p.y, 0.0, 1e-6) << p;
    } else {
      const cv::Point2d d = p - cv::Point2d(0.5, 0.5);
      EXPECT_NEAR(std::sqrt(d.dot(d)), 0.5, 1e-6) << p;
    }
  }
}

}  // namespace
}  // namespace follow_bot
