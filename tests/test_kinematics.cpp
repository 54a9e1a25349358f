// Kinematics of moving walls: each part against its closed form (translation, rotation at 30 rpm,
// oscillation, position and speed tables with their hold behaviour), the composed velocity
// against a central finite difference of the composed pose, the displacement bound against
// sampled points, and the YAML reader's errors (file, line, key path, what is valid).
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "case/spec.h"
#include "motion/kinematics.h"

namespace dem {
namespace {

using Eigen::Vector3d;
constexpr double kPi = std::numbers::pi;

Vector3d apply(const Pose& pose, const Vector3d& local) { return pose.rotation * local + pose.translation; }

MotionPart translation(Vector3d velocity, double start = 0, double stop = INFINITY) {
  MotionPart p;
  p.kind = MotionPart::Kind::translation, p.velocity = velocity, p.start = start, p.stop = stop;
  return p;
}
MotionPart rotation(Vector3d axis, Vector3d point, double angular_speed, double start = 0, double stop = INFINITY) {
  MotionPart p;
  p.kind = MotionPart::Kind::rotation, p.axis = axis.normalized(), p.point = point;
  p.angular_speed = angular_speed, p.start = start, p.stop = stop;
  return p;
}
MotionPart oscillation(Vector3d amplitude, double frequency, double phase, double start = 0, double stop = INFINITY) {
  MotionPart p;
  p.kind = MotionPart::Kind::oscillation, p.amplitude = amplitude, p.frequency = frequency, p.phase = phase;
  p.start = start, p.stop = stop;
  return p;
}
MotionPart table(std::vector<double> times, std::vector<Vector3d> values, bool speeds, double start = 0) {
  MotionPart p;
  p.kind = MotionPart::Kind::table, p.times = std::move(times), p.values = std::move(values);
  p.speeds = speeds, p.start = start;
  return p;
}

TEST(Kinematics, TranslationMovesFromStartAndFreezesAtStop) {
  const Vector3d v(0.1, -0.2, 0.3);  // [m/s]
  const Motion m{{translation(v, 0.5, 2.0)}};
  EXPECT_FALSE(m.is_static());
  EXPECT_LT(m.pose(0.2).translation.norm(), 1e-15);
  EXPECT_LT((m.pose(1.0).translation - v * 0.5).norm(), 1e-15);
  EXPECT_LT((m.pose(3.0).translation - v * 1.5).norm(), 1e-15);  // frozen at stop
  EXPECT_LT((m.velocity(1.0).linear - v).norm(), 1e-15);
  EXPECT_LT(m.velocity(0.2).linear.norm(), 1e-15);
  EXPECT_LT(m.velocity(3.0).linear.norm(), 1e-15);
  EXPECT_LT(m.velocity(1.0).angular.norm(), 1e-15);
  EXPECT_TRUE(Motion{}.is_static());
  EXPECT_TRUE(Motion{{translation(Vector3d::Zero())}}.is_static());
}

TEST(Kinematics, RotationAt30RpmTurnsOnTheCircleAndReturnsAfterTwoSeconds) {
  const Vector3d centre(0.3, -0.1, 0.05);  // [m] a point on the axis
  const double omega = 30 * 2 * kPi / 60;  // [rad/s] = pi
  const Motion m{{rotation(Vector3d::UnitZ(), centre, omega)}};
  const Vector3d start = centre + Vector3d(0.1, 0, 0.02);  // radius 0.1 m from the axis
  for (double t : {0.0, 0.13, 0.5, 0.77, 1.0, 1.5, 2.0, 3.3}) {
    SCOPED_TRACE(t);
    const Vector3d x = apply(m.pose(t), start);
    const Vector3d from_axis = x - centre;
    EXPECT_NEAR(std::hypot(from_axis.x(), from_axis.y()), 0.1, 1e-14);  // on the circle
    EXPECT_NEAR(from_axis.z(), 0.02, 1e-14);                            // in its plane
    EXPECT_NEAR(std::remainder(std::atan2(from_axis.y(), from_axis.x()) - omega * t, 2 * kPi), 0.0, 1e-12);
    const RigidVelocity v = m.velocity(t);
    EXPECT_NEAR(v.at(x).norm(), omega * 0.1, 1e-14);  // speed = omega r
    EXPECT_NEAR(v.at(x).dot(from_axis), 0.0, 1e-14);  // tangential
    EXPECT_LT((v.origin - centre).norm(), 1e-14);     // reference point: on the axis
  }
  EXPECT_LT((apply(m.pose(2.0), start) - start).norm(), 1e-14);  // one full turn
  EXPECT_LT((apply(m.pose(0.5), start) - (centre + Vector3d(0, 0.1, 0.02))).norm(), 1e-14);
}

TEST(Kinematics, OscillationMatchesClosedForm) {
  const Vector3d amplitude(0, 0.001, 0.005);  // [m]
  const double f = 10, phase = 0.3, start = 0.1;
  const Motion m{{oscillation(amplitude, f, phase, start)}};
  EXPECT_LT((m.pose(0.0).translation - amplitude * std::sin(phase)).norm(), 1e-16);  // rests in start pose
  EXPECT_LT(m.velocity(0.05).linear.norm(), 1e-16);
  for (double t : {0.1, 0.1234, 0.37, 1.0}) {
    const double arg = 2 * kPi * f * (t - start) + phase;
    EXPECT_LT((m.pose(t).translation - amplitude * std::sin(arg)).norm(), 1e-15);
    EXPECT_LT((m.velocity(t).linear - amplitude * 2 * kPi * f * std::cos(arg)).norm(), 1e-12);
  }
}

TEST(Kinematics, PositionTableInterpolatesAndHoldsItsEnds) {
  const Motion m{{table({0, 1, 3}, {Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(1, 2, 0)}, false, 0.5)}};
  EXPECT_LT(m.pose(0.2).translation.norm(), 1e-15);
  EXPECT_LT((m.pose(1.0).translation - Vector3d(0.5, 0, 0)).norm(), 1e-15);
  EXPECT_LT((m.pose(2.5).translation - Vector3d(1, 1, 0)).norm(), 1e-15);
  EXPECT_LT((m.pose(10).translation - Vector3d(1, 2, 0)).norm(), 1e-15);  // holds the last row
  EXPECT_LT((m.velocity(1.0).linear - Vector3d(1, 0, 0)).norm(), 1e-15);
  EXPECT_LT((m.velocity(2.5).linear - Vector3d(0, 1, 0)).norm(), 1e-15);
  EXPECT_LT(m.velocity(10).linear.norm(), 1e-15);
  EXPECT_LT(m.velocity(0.2).linear.norm(), 1e-15);
  // Before its first time a table holds the first row.
  const Motion late{{table({1, 2}, {Vector3d(0, 0, 0.2), Vector3d(0, 0, 0.4)}, false)}};
  EXPECT_LT((late.pose(0.5).translation - Vector3d(0, 0, 0.2)).norm(), 1e-15);
  EXPECT_TRUE(Motion{{table({0, 1}, {Vector3d(1, 2, 3), Vector3d(1, 2, 3)}, false)}}.is_static());
}

TEST(Kinematics, SpeedTableIsIntegratedExactly) {
  // Speed ramps 0 -> 2 m/s over 1 s, holds 2 m/s to 2 s, then 1 m/s at 3 s (uneven rows).
  const std::vector<double> times{0, 1, 2, 3.5};
  const std::vector<Vector3d> speeds{Vector3d(0, 0, 0), Vector3d(2, 0, 0), Vector3d(2, 0, 0), Vector3d(-1, 0, 1)};
  const Motion m{{table(times, speeds, true)}};
  // Areas under the piecewise-linear speed, by hand.
  EXPECT_NEAR(m.pose(0.5).translation.x(), 0.25, 1e-15);
  EXPECT_NEAR(m.pose(1.0).translation.x(), 1.0, 1e-15);
  EXPECT_NEAR(m.pose(1.5).translation.x(), 2.0, 1e-15);
  // From 2 s: v(u) = 2 - 2u, w(u) = (2/3) u for u = s - 2 in [0, 1.5].
  EXPECT_LT((m.pose(2.75).translation - Vector3d(3 + 2 * 0.75 - 0.75 * 0.75, 0, 0.75 * 0.75 / 3)).norm(), 1e-14);
  const Vector3d end(3 + 3 - 2.25, 0, 0.75);
  EXPECT_LT((m.pose(3.5).translation - end).norm(), 1e-14);
  EXPECT_LT((m.pose(9.0).translation - end).norm(), 1e-14);  // stops after the last row
  EXPECT_LT(m.velocity(9.0).linear.norm(), 1e-15);
  EXPECT_LT((m.velocity(0.5).linear - Vector3d(1, 0, 0)).norm(), 1e-15);
  EXPECT_LT((m.velocity(2.75).linear - Vector3d(0.5, 0, 0.5)).norm(), 1e-14);
  EXPECT_LT(m.pose(-1).translation.norm(), 1e-15);
  // Integration is consistent with the rate: a finite difference of the position.
  for (double t : {0.3, 1.2, 2.9}) {
    const double h = 1e-6;
    const Vector3d fd = (m.pose(t + h).translation - m.pose(t - h).translation) / (2 * h);
    EXPECT_LT((fd - m.velocity(t).linear).norm(), 1e-8);
  }
}

/// Central difference of pose(t) at body points against velocity(t), and of the rotation against
/// the angular velocity, at random times.
void expect_velocity_matches_pose(const Motion& m, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> time(0.0, 5.0), coordinate(-0.5, 0.5);
  const double h = 1e-5;  // [s]
  for (int trial = 0; trial < 60; ++trial) {
    const double t = time(random);
    SCOPED_TRACE(testing::Message() << "t = " << t);
    const Pose before = m.pose(t - h), now = m.pose(t), after = m.pose(t + h);
    const RigidVelocity v = m.velocity(t);
    for (int k = 0; k < 4; ++k) {
      const Vector3d local(coordinate(random), coordinate(random), coordinate(random));
      const Vector3d fd = (apply(after, local) - apply(before, local)) / (2 * h);
      const Vector3d exact = v.at(apply(now, local));
      EXPECT_LE((fd - exact).norm(), 1e-6 * std::max(1.0, exact.norm()));
    }
    // dq/dt = (w/2) q: w = 2 (dq/dt) q*.
    Eigen::Quaterniond next = after.rotation, last = before.rotation;
    if (next.dot(now.rotation) < 0) next.coeffs() *= -1;
    if (last.dot(now.rotation) < 0) last.coeffs() *= -1;
    Eigen::Quaterniond rate;
    rate.coeffs() = (next.coeffs() - last.coeffs()) / (2 * h);
    const Vector3d angular = 2 * (rate * now.rotation.conjugate()).vec();
    EXPECT_LE((angular - v.angular).norm(), 1e-6 * std::max(1.0, v.angular.norm()));
  }
}

TEST(Kinematics, ComposedVelocityIsTheDerivativeOfTheComposedPose) {
  const Vector3d tilted = Vector3d(0.3, -0.5, 0.8).normalized();
  // Rotation after translation: the rotation's axis is fixed in the world and sweeps the
  // translating body; then a shake on top.
  expect_velocity_matches_pose(Motion{{translation(Vector3d(0.2, 0.1, -0.3), 0.4, 3.7),
                                       rotation(tilted, Vector3d(0.1, 0.2, -0.3), 2.5, 1.1),
                                       oscillation(Vector3d(0.01, 0, 0.02), 3, 0.7)}},
                               1);
  // Translation after rotation, then a second rotation about another axis.
  expect_velocity_matches_pose(Motion{{rotation(Vector3d::UnitZ(), Vector3d(0.5, 0, 0), -1.7),
                                       translation(Vector3d(0, 0.4, 0.1), 0.2, 4.1),
                                       rotation(tilted, Vector3d(-0.2, 0.3, 0.1), 0.9, 0.6, 3.2)}},
                               2);
  // A table of speeds and a table of positions under a rotation.
  expect_velocity_matches_pose(
      Motion{{table({0, 1.3, 2.1, 4.6}, {Vector3d(0, 0, 0), Vector3d(0.2, 0, 0.1), Vector3d(-0.1, 0.3, 0), Vector3d(0, 0, 0)}, true),
              rotation(Vector3d(1, 1, 0), Vector3d(0, 0, 0.3), 3.0, 0.5),
              table({0, 2, 4.5}, {Vector3d(0, 0, 0), Vector3d(0, 0.1, 0.05), Vector3d(0.3, 0, 0)}, false, 0.3)}},
      3);
}

TEST(Kinematics, MaxDisplacementBoundsSampledPointsTightlyForRotation) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), time(0.0, 4.0), span(0.0, 0.3);
  const double radius = 0.4;  // [m]
  const auto sample_in_ball = [&]() {
    Vector3d x;
    do x = Vector3d(unit(random), unit(random), unit(random));
    while (x.norm() > 1.0);
    return Vector3d(radius * x);
  };
  const Motion spinning{{rotation(Vector3d(0, 1, 1), Vector3d(0.1, 0, -0.2), 3.1)}};
  const Motion composed{{translation(Vector3d(0.2, 0.1, -0.3), 0.4, 3.7), rotation(Vector3d(1, 0, 1), Vector3d(0.1, 0.2, -0.3), 2.5, 1.1),
                         oscillation(Vector3d(0.01, 0, 0.02), 3, 0.7)}};
  for (const Motion* m : {&spinning, &composed}) {
    for (int trial = 0; trial < 40; ++trial) {
      const double t0 = time(random), t1 = t0 + span(random);
      const double bound = m->max_displacement(t0, t1, radius);
      const Pose a = m->pose(t0), b = m->pose(t1);
      double largest = 0;
      for (int k = 0; k < 2000; ++k) {
        const Vector3d x = sample_in_ball();
        largest = std::max(largest, (apply(b, x) - apply(a, x)).norm());
      }
      EXPECT_GE(bound, largest);
      if (m == &spinning) {
        EXPECT_LT(bound, 3 * largest);
      }
    }
  }
  EXPECT_LT(Motion{}.max_displacement(0, 1, radius), 1e-14);
}

MotionPart belt_loop(double offset, double speed = 1.5) {
  MotionPart p;
  p.kind = MotionPart::Kind::belt_loop, p.axis = Vector3d::UnitY(), p.lower = Vector3d(0.1, 0.2, -0.3);
  p.upper = p.lower + Vector3d(0, 0, 3), p.radius = 0.3, p.speed = speed, p.offset = offset;
  return p;
}

/// Arc length on the loop of belt_loop(): 3 m straights, 0.3 pi m arcs.
constexpr double kStraight = 3.0, kArc = 0.3 * kPi, kLoop = 2 * kStraight + 2 * kArc;

TEST(Kinematics, BeltLoopClosesAfterOnePeriodAndStartsWhereDocumented) {
  const Motion m{{belt_loop(0.0)}};
  EXPECT_NEAR(belt_loop_length(m.parts[0]), kLoop, 1e-12);
  // Arc length 0: on the up straight (+s = e x axis = z x y = -x), local x outward, y up, z along axis.
  const Pose start = m.pose(0);
  EXPECT_LT((start.translation - Vector3d(0.1 - 0.3, 0.2, -0.3)).norm(), 1e-12);
  EXPECT_LT((start.rotation * Vector3d::UnitX() - Vector3d(-1, 0, 0)).norm(), 1e-12);
  EXPECT_LT((start.rotation * Vector3d::UnitY() - Vector3d(0, 0, 1)).norm(), 1e-12);
  EXPECT_LT((start.rotation * Vector3d::UnitZ() - Vector3d(0, 1, 0)).norm(), 1e-12);
  // Over the top (arc length 3 + 0.15 pi): at the upper pulley's top, moving +x, x outward = +z.
  const Pose top = m.pose((kStraight + kArc / 2) / 1.5);
  EXPECT_LT((top.translation - Vector3d(0.1, 0.2, 2.7 + 0.3)).norm(), 1e-12);
  EXPECT_LT((top.rotation * Vector3d::UnitX() - Vector3d(0, 0, 1)).norm(), 1e-12);
  EXPECT_LT((m.velocity((kStraight + kArc / 2) / 1.5).linear - Vector3d(1.5, 0, 0)).norm(), 1e-12);
  // Closed: one loop length later every body point is back, for any offset and direction.
  for (const double speed : {1.5, -0.7}) {
    const Motion shifted{{belt_loop(0.37, speed)}};
    const double period = kLoop / std::abs(speed);
    for (double t : {0.0, 0.8, 2.3, 5.1}) {
      const Pose a = shifted.pose(t), b = shifted.pose(t + period);
      for (const Vector3d& local : {Vector3d(0, 0, 0), Vector3d(0.14, 0.1, -0.1)})
        EXPECT_LT((apply(a, local) - apply(b, local)).norm(), 1e-9) << "t = " << t;
    }
  }
}

TEST(Kinematics, BeltLoopVelocityIsTheDerivativeOnStraightsAndArcs) {
  const double speed = 1.5;  // [m/s]
  const Motion m{{belt_loop(0.0, speed)}};
  const double h = 1e-6;  // [s]
  // Arc lengths inside each piece: up straight, upper arc, down straight, lower arc.
  const struct { double arc_length; bool on_arc; } samples[] = {
      {0.4, false}, {2.9, false}, {kStraight + 0.1, true}, {kStraight + 0.8, true},
      {kStraight + kArc + 1.7, false}, {2 * kStraight + kArc + 0.2, true}, {kLoop - 0.05, true}};
  for (const auto& sample : samples) {
    const double t = sample.arc_length / speed;
    SCOPED_TRACE(testing::Message() << "arc length " << sample.arc_length);
    const Pose before = m.pose(t - h), now = m.pose(t), after = m.pose(t + h);
    const RigidVelocity v = m.velocity(t);
    EXPECT_LT((v.origin - now.translation).norm(), 1e-12);  // the reference point is on the path
    EXPECT_NEAR(v.linear.norm(), speed, 1e-12);
    EXPECT_NEAR(v.angular.norm(), sample.on_arc ? speed / 0.3 : 0.0, 1e-12);
    if (sample.on_arc) {
      EXPECT_NEAR(v.angular.dot(Vector3d::UnitY()), speed / 0.3, 1e-12);
    }
    for (const Vector3d& local : {Vector3d(0, 0, 0), Vector3d(0.14, 0.1, -0.1), Vector3d(-0.05, 0.2, 0.3)}) {
      const Vector3d fd = (apply(after, local) - apply(before, local)) / (2 * h);
      const Vector3d exact = v.at(apply(now, local));
      EXPECT_LE((fd - exact).norm(), 1e-6 * std::max(1.0, exact.norm()));
    }
  }
  // Composed with a later translation it stays exact (the generic twist composition).
  expect_velocity_matches_pose(Motion{{belt_loop(0.2, 1.1), translation(Vector3d(0.1, 0, 0))}}, 4);
}

TEST(Kinematics, BeltLoopDisplacementBoundHoldsAndStaticWhenStopped) {
  const Motion m{{belt_loop(0.0)}};
  std::mt19937 random(11);
  std::uniform_real_distribution<double> time(0.0, 6.0), span(0.0, 0.5), unit(-0.2, 0.2);
  for (int trial = 0; trial < 40; ++trial) {
    const double t0 = time(random), t1 = t0 + span(random);
    const double bound = m.max_displacement(t0, t1, 0.35);
    for (int k = 0; k < 200; ++k) {
      const Vector3d x(unit(random), unit(random), unit(random));
      EXPECT_GE(bound, (apply(m.pose(t1), x) - apply(m.pose(t0), x)).norm());
    }
  }
  EXPECT_FALSE(m.is_static());
  EXPECT_TRUE((Motion{{belt_loop(0.3, 0.0)}}.is_static()));
}

// ---------------------------------------------------------------------------------------------
// YAML
// ---------------------------------------------------------------------------------------------

class KinematicsYaml : public testing::Test {
 protected:
  void SetUp() override {
    folder_ = std::filesystem::temp_directory_path() /
              ("demdesign_kinematics_" + std::string(testing::UnitTest::GetInstance()->current_test_info()->name()));
    std::filesystem::create_directories(folder_);
  }
  void TearDown() override { std::filesystem::remove_all(folder_); }
  void write(const std::string& name, const std::string& text) { std::ofstream(folder_ / name) << text; }
  /// The motion under meshes.drum.motion of `yaml`, read as if from case.yaml in the folder.
  Motion read(const std::string& yaml) {
    const YAML::Node root = YAML::Load(yaml);
    return read_motion(root["meshes"]["drum"]["motion"], "case.yaml", "meshes.drum.motion", folder_.string());
  }
  /// The error message of reading `yaml`; fails the test when it reads.
  std::string error(const std::string& yaml) {
    try {
      read(yaml);
    } catch (const CaseError& e) {
      return e.what();
    }
    ADD_FAILURE() << "no error for:\n" << yaml;
    return "";
  }
  std::filesystem::path folder_;
};

TEST_F(KinematicsYaml, ReadsTheDocumentedForms) {
  const Motion single = read("meshes:\n  drum:\n    motion: {rotation: {axis: [0, 2, 0], point: [0, 0, 0.2], rpm: 30}, start: 0.1}\n");
  ASSERT_EQ(single.parts.size(), 1u);
  const MotionPart& r = single.parts[0];
  EXPECT_EQ(r.kind, MotionPart::Kind::rotation);
  EXPECT_LT((r.axis - Vector3d::UnitY()).norm(), 1e-15);
  EXPECT_LT((r.point - Vector3d(0, 0, 0.2)).norm(), 1e-15);
  EXPECT_NEAR(r.angular_speed, kPi, 1e-15);
  EXPECT_EQ(r.start, 0.1);
  EXPECT_TRUE(std::isinf(r.stop));

  write("lift.csv", "# lift profile\nt, x, y, z\n0, 0, 0, 0\n\n1.5, 0, 0, 0.1\r\n3, 0, 0, 0.1\n");
  write("ramp.csv", "t,vx,vy,vz\n0,0,0,0\n1,0,0,0.2\n");
  const Motion list = read(R"(
meshes:
  drum:
    motion:
      - {translation: {velocity: [0.1, 0, 0]}, stop: 2.0}
      - {oscillation: {amplitude: [0, 0, 0.005], frequency: 10, phase: 0.5}}
      - {table: {file: lift.csv, columns: position}}
      - {table: {file: ramp.csv}, start: 1}
      - {rotation: {axis: [1, 0, 0], rad_per_s: -2}}
)");
  ASSERT_EQ(list.parts.size(), 5u);
  EXPECT_EQ(list.parts[0].kind, MotionPart::Kind::translation);
  EXPECT_EQ(list.parts[0].stop, 2.0);
  EXPECT_EQ(list.parts[1].frequency, 10.0);
  EXPECT_EQ(list.parts[1].phase, 0.5);
  EXPECT_EQ(list.parts[2].times, (std::vector<double>{0, 1.5, 3}));
  EXPECT_FALSE(list.parts[2].speeds);
  EXPECT_EQ(list.parts[2].values[1], Vector3d(0, 0, 0.1));
  EXPECT_TRUE(list.parts[3].speeds);
  EXPECT_EQ(list.parts[4].angular_speed, -2.0);
  EXPECT_TRUE(read("meshes:\n  drum:\n    motion:\n").is_static());
}

TEST_F(KinematicsYaml, ReadsABeltLoopAndChecksItsPulleys) {
  const Motion m = read("meshes:\n  drum:\n    motion: {belt_loop: {axis: [0, 1, 0], lower: [0, 0, 0], upper: [0, 0, 3], "
                        "radius: 0.3, speed: 1.5, offset: 0.0}}\n");
  ASSERT_EQ(m.parts.size(), 1u);
  EXPECT_EQ(m.parts[0].kind, MotionPart::Kind::belt_loop);
  EXPECT_EQ(m.parts[0].upper, Vector3d(0, 0, 3));
  EXPECT_EQ(m.parts[0].radius, 0.3);
  EXPECT_EQ(m.parts[0].speed, 1.5);
  const std::string skew = error("meshes:\n  drum:\n    motion:\n      belt_loop: {axis: [0, 1, 0], lower: [0, 0, 0], "
                                 "upper: [0, 1, 3], radius: 0.3, speed: 1}\n");
  EXPECT_NE(skew.find("meshes.drum.motion.belt_loop.upper"), std::string::npos) << skew;
  EXPECT_NE(skew.find("perpendicular"), std::string::npos) << skew;
  const std::string radius = error("meshes:\n  drum:\n    motion:\n      belt_loop: {axis: [0, 1, 0], lower: [0, 0, 0], "
                                   "upper: [0, 0, 3], speed: 1}\n");
  EXPECT_NE(radius.find("belt_loop.radius: missing"), std::string::npos) << radius;
}

TEST_F(KinematicsYaml, UnknownKeysNameLineAndSuggestion) {
  const std::string rmp = error("meshes:\n  drum:\n    motion:\n      rotation: {axis: [0, 0, 1], rmp: 30}\n");
  EXPECT_NE(rmp.find("case.yaml:4:"), std::string::npos) << rmp;
  EXPECT_NE(rmp.find("meshes.drum.motion.rotation.rmp"), std::string::npos) << rmp;
  EXPECT_NE(rmp.find("did you mean 'rpm'"), std::string::npos) << rmp;

  const std::string kind = error("meshes:\n  drum:\n    motion:\n      - {rotaton: {axis: [0, 0, 1], rpm: 3}}\n");
  EXPECT_NE(kind.find("case.yaml:4:"), std::string::npos) << kind;
  EXPECT_NE(kind.find("meshes.drum.motion[0].rotaton"), std::string::npos) << kind;
  EXPECT_NE(kind.find("did you mean 'rotation'"), std::string::npos) << kind;

  const std::string none = error("meshes:\n  drum:\n    motion: {start: 1}\n");
  EXPECT_NE(none.find("one of translation, rotation, oscillation, table"), std::string::npos) << none;
  const std::string two = error("meshes:\n  drum:\n    motion: {translation: {velocity: [1, 0, 0]}, rotation: {axis: [0, 0, 1], rpm: 1}}\n");
  EXPECT_NE(two.find("make a list"), std::string::npos) << two;
}

TEST_F(KinematicsYaml, RotationNeedsAnAxisAndOneSpeed) {
  const std::string zero = error("meshes:\n  drum:\n    motion:\n      rotation:\n        axis: [0, 0, 0]\n        rpm: 30\n");
  EXPECT_NE(zero.find("case.yaml:5:"), std::string::npos) << zero;
  EXPECT_NE(zero.find("meshes.drum.motion.rotation.axis"), std::string::npos) << zero;
  EXPECT_NE(zero.find("must not be zero"), std::string::npos) << zero;

  const std::string both = error("meshes:\n  drum:\n    motion:\n      rotation: {axis: [0, 0, 1], rpm: 30, rad_per_s: 3}\n");
  EXPECT_NE(both.find("not both"), std::string::npos) << both;
  EXPECT_NE(both.find("case.yaml:4:"), std::string::npos) << both;
  const std::string neither = error("meshes:\n  drum:\n    motion:\n      rotation: {axis: [0, 0, 1]}\n");
  EXPECT_NE(neither.find("give rpm or rad_per_s"), std::string::npos) << neither;
  const std::string order = error("meshes:\n  drum:\n    motion: {translation: {velocity: [1, 0, 0]}, start: 2, stop: 1}\n");
  EXPECT_NE(order.find("meshes.drum.motion.stop"), std::string::npos) << order;
}

TEST_F(KinematicsYaml, BadCsvNamesTheCsvLineAndTheYamlKey) {
  const std::string yaml = "meshes:\n  drum:\n    motion:\n      - {translation: {velocity: [1, 0, 0]}}\n"
                           "      - {table: {file: lift.csv}}\n";
  const auto expect_error = [&](const std::string& csv, const std::string& where, const std::string& what) {
    write("lift.csv", csv);
    const std::string message = error(yaml);
    EXPECT_NE(message.find("case.yaml:5:"), std::string::npos) << message;
    EXPECT_NE(message.find("meshes.drum.motion[1].table.file"), std::string::npos) << message;
    EXPECT_NE(message.find(where), std::string::npos) << message;
    EXPECT_NE(message.find(what), std::string::npos) << message;
  };
  expect_error("t,x,y,z\n0,0,0,0\n1,0,0,0.1\n2,0,abc,0\n", "lift.csv:4:", "'abc' is not a finite number");
  expect_error("t,x,y,z\n0,0,0,0\n1,0,0,0.1\n1,0,0,0.2\n", "lift.csv:4:", "times must increase");
  expect_error("t,x,y,z\n0,0,0,0\n1,0,0\n", "lift.csv:3:", "3 values; each row needs 4");
  expect_error("time,x,y,z\n0,0,0,0\n", "lift.csv:1:", "valid: t,x,y,z");
  expect_error("t,x,y,z\n0,0,0,0\n", "lift.csv", "at least 2");
  std::filesystem::remove(folder_ / "lift.csv");
  const std::string missing = error(yaml);
  EXPECT_NE(missing.find("lift.csv' not found"), std::string::npos) << missing;
  EXPECT_NE(missing.find("meshes.drum.motion[1].table.file"), std::string::npos) << missing;
  std::filesystem::create_directory(folder_ / "lift.csv");
  EXPECT_NE(error(yaml).find("is a folder"), std::string::npos);
  std::filesystem::remove(folder_ / "lift.csv");

  write("lift.csv", "t,vx,vy,vz\n0,0,0,0\n1,0,0,1\n");
  const std::string mismatch = error("meshes:\n  drum:\n    motion: {table: {file: lift.csv, columns: position}}\n");
  EXPECT_NE(mismatch.find("meshes.drum.motion.table.columns"), std::string::npos) << mismatch;
  EXPECT_NE(mismatch.find("does not match the header"), std::string::npos) << mismatch;
}

}  // namespace
}  // namespace dem
