// Equipment generators without simulation: every generator's defaults make valid meshes; bad
// parameters name file, line, key path and range; the transfer chute's layout holds over a range
// of drop heights, hood and spoon radii (the CEMA trajectory meets the hood, the spoon lip lands
// on the receiving belt); the screw's flight is a helicoid of the given pitch that conveys +x;
// the bucket elevator's pole distance and discharge type; STL output; expand_equipment.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <numbers>
#include <string>

#include "equipment.h"

namespace dem::equipment {
namespace {

constexpr double kPi = std::numbers::pi;

EquipmentSpec make(const std::string& type, const std::string& text) {
  return EquipmentSpec{type, std::make_shared<YAML::Node>(YAML::Load(text)), "<inline>", {}};
}

std::string error_of(const std::string& type, const std::string& text) {
  try {
    generate(make(type, text));
  } catch (const CaseError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for " << type << ":\n" << text;
  return "";
}

const MeshWallSpec& mesh_named(const Generated& g, const std::string& name) {
  for (const MeshWallSpec& m : g.meshes)
    if (m.name == name) return m;
  throw std::runtime_error("no mesh " + name);
}

Vec3 vertex(const MeshWallSpec& m, std::int32_t i) {
  const auto& v = m.vertices[static_cast<size_t>(i)];
  return Vec3(v[0], v[1], v[2]);
}

double design(const Generated& g, const std::string& name) {
  for (const auto& [key, value] : g.design)
    if (key == name) return value;
  ADD_FAILURE() << "no design value " << name;
  return NAN;
}

TEST(Equipment, EveryGeneratorMakesValidMeshesWithDefaults) {
  ASSERT_EQ(generator_names(), (std::vector<std::string>{"transfer_chute", "screw_conveyor", "bucket_elevator", "belt_conveyor", "silo"}));
  for (const std::string& type : generator_names()) {
    SCOPED_TRACE(type);
    const Generated g = generate(make(type, "{}"));
    ASSERT_FALSE(g.meshes.empty());
    EXPECT_FALSE(g.ports.empty());
    EXPECT_FALSE(g.outlets.empty());
    EXPECT_FALSE(g.sensors.empty());
    EXPECT_FALSE(g.design.empty());
    size_t total = 0;
    for (const MeshWallSpec& m : g.meshes) {
      SCOPED_TRACE(m.name);
      EXPECT_FALSE(m.triangles.empty());
      EXPECT_TRUE(m.material == "steel" || m.material == "rubber") << m.material;
      total += m.triangles.size();
      for (const auto& t : m.triangles) {
        for (const std::int32_t i : t) ASSERT_TRUE(i >= 0 && size_t(i) < m.vertices.size());
        const Vec3 a = vertex(m, t[0]), b = vertex(m, t[1]), c = vertex(m, t[2]);
        const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
        EXPECT_GT((b - a).cross(c - a).norm(), 1e-6 * longest * longest) << "degenerate triangle";
        EXPECT_LT(longest, 0.3);  // [m] no long slivers on the big parts
        // The plant lies inside the domain.
        for (const Vec3& p : {a, b, c}) {
          EXPECT_TRUE((p.array() >= g.domain_min.array()).all() && (p.array() <= g.domain_max.array()).all());
        }
      }
    }
    if (type == "transfer_chute") {
      EXPECT_GE(total, 2000u);
      EXPECT_LE(total, 6000u);
    }
    for (const Port& port : g.ports) EXPECT_TRUE((port.region_max.array() > port.region_min.array()).all());
  }
}

TEST(Equipment, ParameterErrorsNameFileLineKeyAndRange) {
  const std::string radius = error_of("transfer_chute", "drop_height: 2\nspoon:\n  radius: 9\n");
  EXPECT_NE(radius.find("<inline>:3:"), std::string::npos) << radius;
  EXPECT_NE(radius.find("equipment.transfer_chute.spoon.radius"), std::string::npos) << radius;
  EXPECT_NE(radius.find("valid: [0.2, 5] m"), std::string::npos) << radius;
  const std::string typo = error_of("transfer_chute", "spon: {radius: 1}\n");
  EXPECT_NE(typo.find("equipment.transfer_chute.spon"), std::string::npos) << typo;
  EXPECT_NE(typo.find("did you mean 'spoon'"), std::string::npos) << typo;
  const std::string inner = error_of("transfer_chute", "hood:\n  radios: 1\n");
  EXPECT_NE(inner.find("<inline>:2:"), std::string::npos) << inner;
  EXPECT_NE(inner.find("did you mean 'radius'"), std::string::npos) << inner;
  const std::string trough = error_of("screw_conveyor", "trough: square\n");
  EXPECT_NE(trough.find("equipment.screw_conveyor.trough"), std::string::npos) << trough;
  EXPECT_NE(trough.find("valid: U, tubular"), std::string::npos) << trough;
  const std::string periodic = error_of("screw_conveyor", "periodic: true\npitch: 0.1\nlength: 0.45\n");
  EXPECT_NE(periodic.find("equipment.screw_conveyor.length"), std::string::npos) << periodic;
  EXPECT_NE(periodic.find("whole number"), std::string::npos) << periodic;
  const std::string both = error_of("bucket_elevator", "belt_speed: 1\nhead_rpm: 40\n");
  EXPECT_NE(both.find("not both"), std::string::npos) << both;
  const std::string type = error_of("screw_conveyer", "{}");
  EXPECT_NE(type.find("did you mean 'screw_conveyor'"), std::string::npos) << type;
  // A null map is the defaults.
  EXPECT_NO_THROW(generate(make("belt_conveyor", "")));
}

// ---------------------------------------------------------------------------------------------
// Transfer chute
// ---------------------------------------------------------------------------------------------

TEST(TransferChute, PulleyAndBeltsMoveTheRightWay) {
  const Generated g = generate(make("transfer_chute", "{}"));
  const MeshWallSpec& pulley = mesh_named(g, "head_pulley");
  ASSERT_EQ(pulley.surface.kind, SurfaceVelocitySpec::Kind::rotation);
  const Vec3 top = pulley.surface.point + Vec3(0, 0, 0.25);  // default R_p
  const Vec3 at_top = pulley.surface.angular_speed * pulley.surface.axis.cross(top - pulley.surface.point);
  EXPECT_LT((at_top - Vec3(2.5, 0, 0)).norm(), 1e-12);  // the top moves with the feed belt
  EXPECT_EQ(mesh_named(g, "feed_belt").surface.velocity, Vec3(2.5, 0, 0));
  EXPECT_EQ(mesh_named(g, "receiving_belt").surface.velocity, Vec3(3.0, 0, 0));
  // The feed belt ends flat at the pulley top, troughed at its tail.
  const MeshWallSpec& feed = mesh_named(g, "feed_belt");
  double tail_top = -1, head_top = -1;
  for (size_t i = 0; i < feed.vertices.size(); ++i) {
    const Vec3 p = vertex(feed, std::int32_t(i));
    if (std::abs(p.x() + 3.0) < 1e-9) tail_top = std::max(tail_top, p.z());
    if (std::abs(p.x()) < 1e-9) head_top = std::max(head_top, p.z());
  }
  EXPECT_NEAR(head_top, 1.5, 1e-12);
  EXPECT_NEAR(tail_top, 1.5 + 0.5 * 0.62 * 0.8 * std::sin(kPi / 6), 1e-9);
  EXPECT_EQ(g.camera, "side");
  EXPECT_LE(g.domain_min.z(), -1.0);
}

/// x [m] where the CEMA high-speed trajectory from the pulley top first leaves the hood circle
/// (the stream leaves at top dead centre: z = H - g x^2 / (2 V^2)); NAN when it starts outside.
double trajectory_exit(const TransferChuteLayout& c) {
  const auto outside = [&](double x) {
    const double z = c.drop_height - 9.81 * x * x / (2 * c.feed_speed * c.feed_speed);
    return std::hypot(x - c.hood_centre_x, z - c.hood_centre_z) >= c.hood_radius;
  };
  if (outside(0)) return NAN;
  double lo = 0, hi = 0;
  while (!outside(hi)) lo = hi, hi += 0.001;
  for (int k = 0; k < 60; ++k) (outside(0.5 * (lo + hi)) ? hi : lo) = 0.5 * (lo + hi);
  return hi;
}

TEST(TransferChute, LayoutHoldsOverARangeOfDropHeightsAndRadii) {
  for (const double drop : {1.0, 1.5, 2.0, 3.0})
    for (const double hood : {0.6, 1.0, 1.5})
      for (const double spoon : {0.5, 0.8, 1.2})
        for (const double speed : {2.0, 2.5, 4.0}) {
          const std::string text = "drop_height: " + std::to_string(drop) + "\nhood: {radius: " + std::to_string(hood) +
                                   "}\nspoon: {radius: " + std::to_string(spoon) + "}\nfeed_belt: {speed: " +
                                   std::to_string(speed) + "}\n";
          SCOPED_TRACE(text);
          const TransferChuteLayout c = transfer_chute_layout(make("transfer_chute", text));
          // The high-speed case applies: V^2 / (g r) >= 1 with r = R_p + a1.
          ASSERT_GE(speed * speed / (9.81 * (c.pulley_radius + 0.5 * c.load_height)), 1.0);
          // The trajectory starts inside the hood circle and meets the arc between its top and end.
          const double x = trajectory_exit(c);
          ASSERT_FALSE(std::isnan(x)) << "the pulley top is outside the hood";
          const double z = c.drop_height - 9.81 * x * x / (2 * speed * speed);
          const double angle = std::atan2(z - c.hood_centre_z, x - c.hood_centre_x);
          EXPECT_GE(angle, c.hood_end_angle + 0.05);
          EXPECT_LE(angle, kPi / 2);
          // ... inside the side plates, not past them.
          EXPECT_TRUE(x > c.side_x_min && x < c.side_x_max && z > c.side_z_min && z < c.side_z_max);
          // The hood top clears the load on the belt.
          EXPECT_GT(c.hood_top_height, c.load_height);
          // Spoon: below and behind the hood exit, lip above the receiving belt and on it.
          EXPECT_LT(c.spoon_top_z, c.hood_exit_z);
          EXPECT_LT(c.spoon_top_x, c.hood_exit_x);
          EXPECT_GT(c.spoon_lip_height, 0.0);
          EXPECT_GT(c.spoon_lip_x, c.receiving_x_min + 0.5);
          EXPECT_LT(c.spoon_lip_x, c.receiving_x_max - 0.5);
          EXPECT_GT(c.spoon_start_angle, 0.25);
          EXPECT_LE(c.spoon_start_angle, kPi / 2 + 1e-12);
          EXPECT_GE(c.back_plate_top, c.hood_exit_z);
          // The receiving belt runs under the whole chute (dribble from the pulley lands on it).
          EXPECT_LT(c.receiving_x_min, c.side_x_min);
          EXPECT_LE(c.spoon_lip_x, c.side_x_max);
        }
  // The spoon is a full quarter when it fits under the hood exit, else cut; its lip lies
  // exit_angle_deg before the bottom of the arc.
  const TransferChuteLayout small = transfer_chute_layout(make("transfer_chute", "spoon: {radius: 0.25}\n"));
  EXPECT_NEAR(small.spoon_start_angle, kPi / 2, 1e-12);
  EXPECT_NEAR(small.spoon_top_x, small.spoon_centre_x - 0.25, 1e-12);
  EXPECT_NEAR(small.spoon_lip_x, small.spoon_centre_x - 0.25 * std::sin(15 * kPi / 180), 1e-12);
  EXPECT_NEAR(small.spoon_centre_z - 0.25 * std::cos(15 * kPi / 180), small.spoon_lip_height, 1e-12);
  // A hood that cannot fit is an error naming the drop height.
  const std::string message = error_of("transfer_chute", "drop_height: 0.4\nhood: {radius: 2}\n");
  EXPECT_NE(message.find("equipment.transfer_chute.drop_height"), std::string::npos) << message;
}

// ---------------------------------------------------------------------------------------------
// Screw conveyor
// ---------------------------------------------------------------------------------------------

TEST(ScrewConveyor, FlightIsAHelicoidOfThePitchThatConveysPlusX) {
  for (const double rpm : {30.0, -45.0}) {
    const Generated g = generate(make("screw_conveyor", "pitch: 0.08\nrpm: " + std::to_string(rpm) + "\n"));
    const MeshWallSpec& screw = mesh_named(g, "screw");
    ASSERT_EQ(screw.motion.parts.size(), 1u);
    const MotionPart& turn = screw.motion.parts[0];
    ASSERT_EQ(turn.kind, MotionPart::Kind::rotation);
    EXPECT_LT((turn.axis - Vec3::UnitX()).norm(), 1e-12);
    const Vec3 centre = turn.point;
    // Tip vertices (r = D/2) advance one pitch in x per turn of angle.
    std::vector<Vec3> tip;
    for (size_t i = 0; i < screw.vertices.size(); ++i) {
      const Vec3 p = vertex(screw, std::int32_t(i));
      if (std::abs(std::hypot(p.y() - centre.y(), p.z() - centre.z()) - 0.05) < 1e-9) tip.push_back(p);
    }
    std::sort(tip.begin(), tip.end(), [](const Vec3& a, const Vec3& b) { return a.x() < b.x(); });
    ASSERT_GT(tip.size(), 100u);
    double phi = std::atan2(tip[0].z() - centre.z(), tip[0].y() - centre.y()), turned = 0;
    for (size_t k = 1; k < tip.size(); ++k) {
      const double next = std::atan2(tip[k].z() - centre.z(), tip[k].y() - centre.y());
      turned += std::remainder(next - phi, 2 * kPi), phi = next;
      EXPECT_NEAR(tip[k].x() - tip[0].x(), 0.08 * turned / (2 * kPi), 1e-9);
    }
    EXPECT_NEAR(tip.back().x() - tip.front().x(), 4 * 0.08, 1e-9);  // default length: 4 pitches
    // The flight's normal velocity pushes material along +x for positive rpm.
    int pushed = 0;
    for (const auto& t : screw.triangles) {
      const Vec3 a = vertex(screw, t[0]), b = vertex(screw, t[1]), c = vertex(screw, t[2]);
      const auto radius = [&](const Vec3& p) { return std::hypot(p.y() - centre.y(), p.z() - centre.z()); };
      if (std::min({radius(a), radius(b), radius(c)}) < 0.015 + 1e-6 + 0.002) continue;  // shaft and root
      const Vec3 n = (b - a).cross(c - a).normalized();
      const Vec3 v = turn.angular_speed * turn.axis.cross((a + b + c) / 3 - centre);
      const double push = v.dot(n) * n.x();
      EXPECT_GT(push * rpm, 0.0);
      ++pushed;
    }
    EXPECT_GT(pushed, 100);
    EXPECT_NEAR(design(g, "swept_area_m2"), kPi / 4 * (0.01 - 0.0009), 1e-12);
    EXPECT_NEAR(design(g, "theoretical_volume_rate_m3_s"), kPi / 4 * (0.01 - 0.0009) * 0.08 * std::abs(rpm) / 60, 1e-12);
    EXPECT_EQ(g.camera, "iso");
  }
}

TEST(ScrewConveyor, PeriodicAndTubularVariants) {
  const Generated periodic = generate(make("screw_conveyor", "periodic: true\nlength: 0.3\n"));
  EXPECT_TRUE(periodic.ports.empty());
  EXPECT_TRUE(periodic.outlets.empty());
  EXPECT_EQ(periodic.domain_min.x(), 0.0);
  EXPECT_EQ(periodic.domain_max.x(), 0.3);
  double x_min = 1e9, x_max = -1e9;
  for (const auto& v : mesh_named(periodic, "screw").vertices) x_min = std::min(x_min, v[0]), x_max = std::max(x_max, v[0]);
  EXPECT_NEAR(x_min, -0.1, 1e-9);
  EXPECT_NEAR(x_max, 0.4, 1e-9);
  const Generated tube = generate(make("screw_conveyor", "trough: tubular\nflight_thickness: 0.004\ninclination_deg: 20\n"));
  const MotionPart& turn = mesh_named(tube, "screw").motion.parts.at(0);
  EXPECT_NEAR(turn.axis.z(), std::sin(20 * kPi / 180), 1e-12);  // the +x end is raised
  EXPECT_FALSE(tube.ports.empty());
}

// ---------------------------------------------------------------------------------------------
// Bucket elevator
// ---------------------------------------------------------------------------------------------

TEST(BucketElevator, PoleDistanceAndDischargeType) {
  // Defaults: R_p 0.25, belt 0.01: r_i = 0.26, r_a = 0.40.
  const struct { double rpm; int type; } cases[] = {{30, 0}, {50, 1}, {60, 2}};
  for (const auto& c : cases) {
    const Generated g = generate(make("bucket_elevator", "head_rpm: " + std::to_string(c.rpm) + "\n"));
    const double omega = c.rpm * 2 * kPi / 60;
    EXPECT_NEAR(design(g, "pole_distance_m"), 9.81 / (omega * omega), 1e-12);
    EXPECT_NEAR(design(g, "inner_lip_radius_m"), 0.26, 1e-12);
    EXPECT_NEAR(design(g, "outer_lip_radius_m"), 0.40, 1e-12);
    EXPECT_EQ(design(g, "discharge_type"), c.type) << c.rpm << " rpm";
  }
  const Generated g = generate(make("bucket_elevator", "{}"));
  EXPECT_NEAR(design(g, "belt_speed_m_s"), 1.5, 1e-12);
  // Buckets fill the loop evenly and ride on it, each with its own belt_loop part.
  const int count = int(design(g, "bucket_count"));
  const double loop = 2 * 3.0 + 2 * kPi * 0.26;
  EXPECT_NEAR(count * design(g, "bucket_spacing_m"), loop, 1e-12);
  int buckets = 0;
  for (const MeshWallSpec& m : g.meshes) {
    if (m.name.rfind("bucket_", 0) != 0) continue;
    ASSERT_EQ(m.motion.parts.size(), 1u);
    const MotionPart& part = m.motion.parts[0];
    EXPECT_EQ(part.kind, MotionPart::Kind::belt_loop);
    EXPECT_NEAR(part.offset, buckets * loop / count, 1e-12);
    EXPECT_NEAR(belt_loop_length(part), loop, 1e-12);
    ++buckets;
  }
  EXPECT_EQ(buckets, count);
  // Bucket 0 starts at the bottom of the rising leg (x = -r_i), opening up, projecting to -x.
  const MeshWallSpec& first = mesh_named(g, "bucket_0");
  const Pose pose = first.motion.pose(0);
  EXPECT_LT((pose.translation - Vec3(-0.26, 0, 0)).norm(), 1e-12);
  for (const auto& v : first.vertices) EXPECT_LE((pose.rotation * Vec3(v[0], v[1], v[2]) + pose.translation).x(), -0.26 + 1e-12);
  // The rising leg moves up with the buckets; the head pulley turns with the belt.
  EXPECT_GT(mesh_named(g, "belt_up").surface.velocity.z(), 0);
  const MeshWallSpec& head = mesh_named(g, "head_pulley");
  const Vec3 rising = head.surface.angular_speed * head.surface.axis.cross(Vec3(-0.26, 0, 0));
  EXPECT_NEAR(rising.z(), first.motion.velocity(0).linear.z(), 1e-12);
}

// ---------------------------------------------------------------------------------------------
// Belt conveyor
// ---------------------------------------------------------------------------------------------

TEST(BeltConveyor, CemaDischargeAtTheTangentPointWhenFastEnough) {
  const Generated fast = generate(make("belt_conveyor", "speed: 2.0\n"));
  const double r = 0.25 + 0.015 + 0.05;
  EXPECT_NEAR(design(fast, "discharge_radius_m"), r, 1e-12);
  EXPECT_NEAR(design(fast, "discharge_ratio_v2_gr"), 4.0 / (9.81 * r), 1e-12);
  EXPECT_EQ(design(fast, "discharge_at_tangent"), 1.0);
  const Generated slow = generate(make("belt_conveyor", "speed: 1.0\n"));
  EXPECT_EQ(design(slow, "discharge_at_tangent"), 0.0);
  EXPECT_NEAR(design(slow, "discharge_angle_from_vertical_deg"), std::acos(1.0 / (9.81 * r)) * 180 / kPi, 1e-9);
  // The discharge outlet lies below the belt beyond the head pulley.
  EXPECT_LT(fast.outlets[0].region_max.z(), -0.5);
  EXPECT_GT(fast.outlets[0].region_max.x(), 8.0);
  const Generated inclined = generate(make("belt_conveyor", "inclination_deg: 10\n"));
  EXPECT_NEAR(mesh_named(inclined, "belt").surface.velocity.z(), 2.0 * std::sin(10 * kPi / 180), 1e-12);
}

TEST(Silo, ShutterSlidesClearOfTheOrificeAtOpenAt) {
  const Generated g = generate(make("silo", "{diameter: 0.125, height: 0.16, orifice_diameter: 0.04, open_at: 0.45}"));
  const MeshWallSpec& gate = mesh_named(g, "shutter");
  EXPECT_LT(gate.motion.pose(0.44).translation.norm(), 1e-15);
  const double moved = gate.motion.pose(10).translation.x();
  EXPECT_GT(moved, 0.02 + 0.025);  // orifice radius + gate radius: clear of the hole
  EXPECT_LT(g.domain_max.z(), 1.0);
  EXPECT_GE(g.domain_max.z(), 0.48);
  EXPECT_GE(g.domain_max.x(), 0.0625 + moved);
  // Without open_at the orifice is open from the start.
  for (const MeshWallSpec& m : generate(make("silo", "{}")).meshes) EXPECT_NE(m.name, "shutter");
}

// ---------------------------------------------------------------------------------------------
// Expansion into a case and STL output
// ---------------------------------------------------------------------------------------------

TEST(Equipment, ExpandFillsPortsDomainAndDesign) {
  CaseSpec spec;
  spec.equipment = make("transfer_chute", "{}");
  InletSpec feed;
  feed.name = "feed", feed.port = "feed_belt";
  spec.inlets.push_back(feed);
  expand_equipment(spec);
  EXPECT_GE(spec.meshes.size(), 6u);
  EXPECT_TRUE(spec.simulation.has_domain);
  EXPECT_EQ(spec.inlets[0].velocity, Vec3(2.5, 0, 0));
  EXPECT_LT(spec.inlets[0].region_min.x(), -2.5);
  EXPECT_GT(spec.inlets[0].region_min.z(), 1.5);
  EXPECT_EQ(spec.equipment_camera, "side");
  EXPECT_FALSE(spec.design.empty());
  EXPECT_EQ(spec.outlets.size(), 1u);
  EXPECT_EQ(spec.sensors.size(), 3u);

  const auto message = [](CaseSpec s) {
    try {
      expand_equipment(s);
    } catch (const CaseError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  CaseSpec wrong_port;
  wrong_port.equipment = make("transfer_chute", "{}");
  feed.port = "feed_bolt";
  wrong_port.inlets.push_back(feed);
  const std::string bad = message(wrong_port);
  EXPECT_NE(bad.find("valid: feed_belt"), std::string::npos) << bad;
  EXPECT_NE(bad.find("did you mean 'feed_belt'"), std::string::npos) << bad;
  CaseSpec no_equipment;
  no_equipment.inlets.push_back(feed);
  EXPECT_NE(message(no_equipment).find("no `equipment:` section"), std::string::npos);
  CaseSpec clash;
  clash.equipment = make("transfer_chute", "{}");
  clash.meshes.push_back(MeshWallSpec{});
  clash.meshes.back().name = "hood";
  EXPECT_NE(message(clash).find("'hood'"), std::string::npos);
}

TEST(Equipment, ErrorsFromACaseFileNameItsLines) {
  // The parameters as the case reader keeps them: the node under the type key of the whole file,
  // so marks are lines of the case file. (parse_case_text is not used: its `equipment:` wiring
  // lives in src/case/spec_walls.cpp.)
  const char* text = R"(simulation: {duration: 0.1}
materials:
  ore: {density: 2600, youngs_modulus: 5e7}
equipment:
  transfer_chute:
    drop_height: 2.0
    hood:
      radius: 0.1
)";
  const YAML::Node root = YAML::Load(text);
  CaseSpec spec;
  spec.equipment = EquipmentSpec{"transfer_chute", std::make_shared<YAML::Node>(root["equipment"]["transfer_chute"]),
                                 "chute.yaml", {"chute.yaml", 5, 3}};
  try {
    expand_equipment(spec);
    ADD_FAILURE() << "no error";
  } catch (const CaseError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("chute.yaml:8:"), std::string::npos) << message;
    EXPECT_NE(message.find("equipment.transfer_chute.hood.radius"), std::string::npos) << message;
    EXPECT_NE(message.find("valid: [0.2, 5] m"), std::string::npos) << message;
  }
}

TEST(Equipment, WritesReadableBinaryStl) {
  CaseSpec spec;
  spec.equipment = make("screw_conveyor", "{}");
  expand_equipment(spec);
  const auto folder = std::filesystem::temp_directory_path() / "demdesign_equipment_stl";
  std::filesystem::remove_all(folder);
  const std::vector<std::string> paths = write_equipment_meshes(spec, folder.string());
  ASSERT_EQ(paths.size(), spec.meshes.size());
  for (size_t k = 0; k < paths.size(); ++k) {
    EXPECT_EQ(std::filesystem::file_size(paths[k]), 84 + 50 * spec.meshes[k].triangles.size()) << paths[k];
    EXPECT_EQ(std::filesystem::path(paths[k]).filename().string(), spec.meshes[k].name + ".stl");
  }
  std::filesystem::remove_all(folder);
}

}  // namespace
}  // namespace dem::equipment
