// Equipment generators without simulation: every generator's defaults make valid meshes; bad
// parameters name file, line, key path and range; the transfer chute's layout holds over a range
// of drop heights, hood and spoon radii (the CEMA trajectory meets the hood, the spoon lip lands
// on the receiving belt); plan angle 0 is the inline chute bit for bit, a turned spoon delivers
// along the receiving belt, centred, and the deck closes an angled chute's two boxes; the rock
// box's ledge lies under the impact point; the profile spoon's and rock box's checks; the
// screw's flight is a helicoid of the given pitch that conveys +x; the bucket elevator's pole
// distance and discharge type; STL output; expand_equipment.
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
// Angled transfer, rock box, profile spoon
// ---------------------------------------------------------------------------------------------

/// A transfer chute spec whose case feeds particles up to `largest` [m] across.
EquipmentSpec chute_with_particles(const std::string& text, double largest) {
  EquipmentSpec spec = make("transfer_chute", text);
  spec.largest_particle = largest;
  return spec;
}

std::string chute_error(const EquipmentSpec& spec) {
  try {
    generate(spec);
  } catch (const CaseError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error";
  return "";
}

/// The equipment of cases/angled_transfer.yaml (iron ore, 1,000 t/h, 90 deg, rock box).
const char* kAngledChute = R"(plan_angle_deg: 90
drop_height: 3.0
chute_width: 1.0
feed_belt: {width: 1.2, speed: 4.0, troughing_angle_deg: 35, length: 4.0, pulley_diameter: 0.8, load_height: 0.15, port_height: 0.35}
hood: {radius: 1.5}
rock_box: {height: 0.3, ledge_depth: 0.35}
spoon: {radius: 1.6, lip_height: 0.25, setback: 0.15, exit_angle_deg: 15}
receiving_belt: {width: 1.2, speed: 4.5, troughing_angle_deg: 35, length: 4.0, skirt_length: 2.0, skirt_height: 0.4}
)";

/// A profile spoon (the one of cases/angled_transfer_sweep.yaml) with `shape`.
std::string profile_spoon(const std::string& shape) {
  return "spoon: {profile: [[-0.65, 1.35], [-0.62, 1.05], [-0.5, 0.75], [-0.25, 0.48], [0.15, 0.3], [0.6, 0.24]], "
         "width: 1.0, shape: " + shape + "}\n";
}

/// The chute of kAngledChute at `angle_deg`, with the arc spoon or a profile spoon of `shape`.
std::string angled(double angle_deg, const std::string& shape = "") {
  std::string text = kAngledChute;
  text.replace(0, text.find('\n'), "plan_angle_deg: " + std::to_string(angle_deg));
  if (!shape.empty()) text.replace(text.find("spoon: {radius"), text.find("receiving_belt") - text.find("spoon: {radius"), profile_spoon(shape));
  return text;
}

/// World point of the receiving frame (x along the receiving belt) turned by the plan angle about
/// the fall line; written out here, independent of the generator's.
Vec3 to_world(const TransferChuteLayout& c, const Vec3& local) {
  const double cos_a = std::cos(c.plan_angle), sin_a = std::sin(c.plan_angle), x = local.x() - c.fall_x;
  return Vec3(c.fall_x + cos_a * x - sin_a * local.y(), sin_a * x + cos_a * local.y(), local.z());
}
Vec3 to_local(const TransferChuteLayout& c, const Vec3& world) {
  const double cos_a = std::cos(c.plan_angle), sin_a = std::sin(c.plan_angle), x = world.x() - c.fall_x;
  return Vec3(c.fall_x + cos_a * x + sin_a * world.y(), -sin_a * x + cos_a * world.y(), world.z());
}

void expect_same_output(const Generated& a, const Generated& b) {
  ASSERT_EQ(a.meshes.size(), b.meshes.size());
  for (size_t m = 0; m < a.meshes.size(); ++m) {
    SCOPED_TRACE(a.meshes[m].name);
    EXPECT_EQ(a.meshes[m].name, b.meshes[m].name);
    EXPECT_EQ(a.meshes[m].vertices, b.meshes[m].vertices);  // bit for bit
    EXPECT_EQ(a.meshes[m].triangles, b.meshes[m].triangles);
    EXPECT_EQ(a.meshes[m].surface.velocity, b.meshes[m].surface.velocity);
    EXPECT_EQ(a.meshes[m].material, b.meshes[m].material);
  }
  ASSERT_EQ(a.sensors.size(), b.sensors.size());
  for (size_t k = 0; k < a.sensors.size(); ++k) {
    EXPECT_EQ(a.sensors[k].point, b.sensors[k].point);
    EXPECT_EQ(a.sensors[k].normal, b.sensors[k].normal);
    EXPECT_EQ(a.sensors[k].region_min, b.sensors[k].region_min);
    EXPECT_EQ(a.sensors[k].region_max, b.sensors[k].region_max);
  }
  ASSERT_EQ(a.outlets.size(), b.outlets.size());
  EXPECT_EQ(a.outlets[0].region_min, b.outlets[0].region_min);
  EXPECT_EQ(a.outlets[0].region_max, b.outlets[0].region_max);
  EXPECT_EQ(a.domain_min, b.domain_min);
  EXPECT_EQ(a.domain_max, b.domain_max);
  EXPECT_EQ(a.design, b.design);
  EXPECT_EQ(a.camera, b.camera);
}

// The inline chute is plan angle 0: the key at 0 changes nothing, bit for bit, and the inline
// chute keeps its parts and their layout (the code path at 0 is the inline one, untouched).
TEST(TransferChute, PlanAngleZeroIsTheInlineChute) {
  const std::string shipped = "drop_height: 1.5\nchute_width: 0.7\nfeed_belt: {width: 0.8, speed: 2.5, troughing_angle_deg: 30, "
                              "length: 3.0, pulley_diameter: 0.5}\nhood: {radius: 1.0, exit_angle_deg: 5}\nspoon: {radius: 0.8, "
                              "lip_height: 0.15, setback: 0.25, exit_angle_deg: 15}\nreceiving_belt: {width: 0.8, speed: 3.0, "
                              "troughing_angle_deg: 30, length: 3.0}\n";
  const std::string profile = "spoon: {profile: [[-0.2, 0.4], [-0.1, 0.25], [0.3, 0.12]]}\n";
  for (const std::string& text : {std::string(""), shipped, std::string("rock_box: {}\n"), profile}) {
    SCOPED_TRACE(text);
    expect_same_output(generate(make("transfer_chute", text)), generate(make("transfer_chute", text + "plan_angle_deg: 0\n")));
  }
  const Generated g = generate(make("transfer_chute", shipped));
  std::vector<std::string> names;
  for (const MeshWallSpec& m : g.meshes) names.push_back(m.name);
  EXPECT_EQ(names, (std::vector<std::string>{"feed_belt", "head_pulley", "hood", "spoon", "side_plates", "receiving_belt", "skirts"}));
  // The spoon's arc and back plate where the layout puts them, across the chute's width.
  const TransferChuteLayout c = transfer_chute_layout(make("transfer_chute", shipped));
  EXPECT_EQ(c.fall_x, c.hood_exit_x);
  EXPECT_EQ(c.spoon_top_x, c.hood_exit_x - 0.25);
  for (const auto& v : mesh_named(g, "spoon").vertices) {
    const bool on_arc = std::abs(std::hypot(v[0] - c.spoon_centre_x, v[2] - c.spoon_centre_z) - c.spoon_radius) < 1e-9;
    const bool on_back = std::abs(v[0] - c.spoon_top_x) < 1e-12 && v[2] >= c.spoon_top_z - 1e-12 && v[2] <= c.back_plate_top + 1e-12;
    EXPECT_TRUE(on_arc || on_back) << v[0] << " " << v[2];
    EXPECT_LE(std::abs(v[1]), 0.35 + 1e-12);
  }
  EXPECT_EQ(mesh_named(g, "receiving_belt").surface.velocity, Vec3(3.0, 0, 0));
  EXPECT_EQ(g.camera, "side");
  for (const auto& entry : g.design) EXPECT_NE(entry.first, "plan_angle_deg");
}

/// Mean of the spoon vertices at the lowest and at the next height: the arc's last two rows.
std::pair<Vec3, Vec3> lip_rows(const MeshWallSpec& spoon) {
  std::vector<double> heights;
  for (const auto& v : spoon.vertices) heights.push_back(v[2]);
  std::sort(heights.begin(), heights.end());
  const double lowest = heights.front();
  const double next = *std::find_if(heights.begin(), heights.end(), [&](double z) { return z > lowest + 1e-9; });
  Vec3 lip = Vec3::Zero(), before = Vec3::Zero();
  int n_lip = 0, n_before = 0;
  for (const auto& v : spoon.vertices) {
    if (std::abs(v[2] - lowest) < 1e-9) lip += Vec3(v[0], v[1], v[2]), ++n_lip;
    if (std::abs(v[2] - next) < 1e-9) before += Vec3(v[0], v[1], v[2]), ++n_before;
  }
  return {lip / n_lip, before / n_before};
}

/// [deg] Angle between the horizontal parts of two directions.
double plan_angle_between(const Vec3& a, const Vec3& b) {
  const Vec3 p(a.x(), a.y(), 0), q(b.x(), b.y(), 0);
  return std::acos(std::clamp(p.normalized().dot(q.normalized()), -1.0, 1.0)) * 180 / kPi;
}

// At 90 deg (and at other angles) the spoon turns the stream into the receiving belt's direction
// of travel: its lip slopes down along the belt within 2 deg, centred on the belt's centre line.
TEST(TransferChute, AngledSpoonDeliversAlongTheReceivingBelt) {
  for (const double angle : {90.0, 30.0, 135.0, 180.0}) {
    SCOPED_TRACE(angle);
    const EquipmentSpec spec = make("transfer_chute", angled(angle));
    const Generated g = generate(spec);
    const TransferChuteLayout c = transfer_chute_layout(spec);
    const Vec3 belt = mesh_named(g, "receiving_belt").surface.velocity;
    const Vec3 travel(std::cos(angle * kPi / 180), std::sin(angle * kPi / 180), 0);
    EXPECT_LT((belt - 4.5 * travel).norm(), 1e-12);
    const auto [lip, before] = lip_rows(mesh_named(g, "spoon"));
    const Vec3 exit = lip - before;
    EXPECT_LT(exit.z(), 0.0) << "the lip slopes down onto the belt";
    EXPECT_LT(plan_angle_between(exit, belt), 2.0);
    // Centred: the lip's middle lies on the belt's centre line through the fall line.
    const Vec3 from_fall = lip - Vec3(c.fall_x, 0, lip.z());
    EXPECT_LT(std::abs(from_fall.x() * travel.y() - from_fall.y() * travel.x()), 1e-9);
    EXPECT_NEAR(lip.z(), 0.25, 1e-9);
    EXPECT_EQ(g.camera, "iso");
  }
  // A profile spoon (rectangular: its floor is the polyline) leaves along its last segment, which
  // the turn lays along the belt.
  const EquipmentSpec spec = make("transfer_chute", angled(90, "rectangular"));
  const TransferChuteLayout c = transfer_chute_layout(spec);
  const Generated g = generate(spec);
  std::vector<Vec3> floor_lip, floor_before;
  for (const auto& v : mesh_named(g, "spoon").vertices) {
    const Vec3 local = to_local(c, Vec3(v[0], v[1], v[2]));
    if (std::abs(local.y()) > 0.5 - 1e-6) continue;  // the walls and the back plate's edges
    if (std::abs(local.x() - (c.fall_x + 0.6)) < 1e-9) floor_lip.push_back(Vec3(v[0], v[1], v[2]));
    if (local.x() < c.fall_x + 0.6 - 1e-9 && local.x() > c.fall_x + 0.6 - 0.15 && std::abs(local.z() - (0.3 - 0.06 * (local.x() - c.fall_x - 0.15) / 0.45)) < 1e-9)
      floor_before.push_back(Vec3(v[0], v[1], v[2]));
  }
  ASSERT_FALSE(floor_lip.empty());
  ASSERT_FALSE(floor_before.empty());
  const Vec3 exit = floor_lip.front() - floor_before.front();
  EXPECT_LT(plan_angle_between(exit, mesh_named(g, "receiving_belt").surface.velocity), 2.0);
}

// The rock box's ledge lies under the point where the CEMA trajectory meets the hood: the dam's
// top, the bed's surface there, within 1e-6 m of the impact height; the dam behind the impact
// point with the trajectory at least 0.05 m above it; the ledge reaching the hood; the spoon under
// the dam, where the stream now comes down.
TEST(TransferChute, RockBoxLedgeLiesWhereTheTrajectoryMeetsTheHood) {
  for (const std::string& text : {std::string("rock_box: {}\n"), std::string(kAngledChute), std::string("rock_box: {ledge_width: 0.5}\n")}) {
    SCOPED_TRACE(text);
    const TransferChuteLayout c = transfer_chute_layout(make("transfer_chute", text));
    const Generated g = generate(make("transfer_chute", text));
    const double x = trajectory_exit(c);  // this test's own search
    const double z = c.drop_height - 9.81 * x * x / (2 * c.feed_speed * c.feed_speed);
    EXPECT_NEAR(c.impact_x, x, 1e-6);
    EXPECT_NEAR(c.impact_z, z, 1e-6);
    const MeshWallSpec& box = mesh_named(g, "rock_box");
    double top = -1e9, bottom = 1e9, back = 1e9, front = -1e9;
    for (const auto& v : box.vertices)
      top = std::max(top, v[2]), bottom = std::min(bottom, v[2]), back = std::min(back, v[0]), front = std::max(front, v[0]);
    EXPECT_NEAR(top, z, 1e-6) << "the dam's top is at the impact height";
    EXPECT_NEAR(top - bottom, c.rock_box_height, 1e-9);
    EXPECT_NEAR(back, c.dam_x, 1e-12);
    EXPECT_LT(back, x) << "the dam stands behind the impact point";
    EXPECT_GE(c.drop_height - 9.81 * back * back / (2 * c.feed_speed * c.feed_speed), z + 0.05 - 1e-9) << "the stream passes over the dam";
    EXPECT_NEAR(std::hypot(front - c.hood_centre_x, bottom - c.hood_centre_z), c.hood_radius, 1e-9) << "the ledge reaches the hood";
    EXPECT_GT(back, c.pulley_radius);
    EXPECT_EQ(c.fall_x, std::min(c.hood_exit_x, c.dam_x));
    EXPECT_GT(design(g, "rock_box_volume_m3"), 0.0);
  }
}

TEST(TransferChute, AngledRockBoxAndProfileParametersAreChecked) {
  const auto expect = [](const std::string& message, std::initializer_list<const char*> parts) {
    for (const char* part : parts) EXPECT_NE(message.find(part), std::string::npos) << part << " in: " << message;
  };
  expect(error_of("transfer_chute", "plan_angle_deg: 200\n"), {"equipment.transfer_chute.plan_angle_deg", "valid: [0, 180] deg"});
  // A profile with a rising segment, naming the point and what is valid.
  expect(error_of("transfer_chute", "spoon:\n  profile: [[-0.2, 1.0], [0.1, 0.6], [0.4, 0.7]]\n"),
         {"<inline>:2:", "equipment.transfer_chute.spoon.profile[2]", "descend monotonically", "valid: z < 0.6 m"});
  expect(error_of("transfer_chute", "spoon: {profile: [[-0.2, 1.0]]}\n"), {"equipment.transfer_chute.spoon.profile", "2 to 100 points"});
  expect(error_of("transfer_chute", "spoon: {profile: [[-0.2, 1.0], [-0.3, 0.5]]}\n"), {"spoon.profile[1]", "runs back"});
  expect(error_of("transfer_chute", "spoon: {profile: [[0.2, 1.0], [0.5, 0.5]]}\n"), {"spoon.profile[0]", "valid: x <= 0"});
  expect(error_of("transfer_chute", "spoon: {profile: [[-0.2, 1.0], [0.5, 0.5]], radius: 1}\n"), {"equipment.transfer_chute.spoon.radius", "not both"});
  expect(error_of("transfer_chute", "spoon: {profile: [[-0.2, 1.0], [0.5, 0.5]], shape: V}\n"), {"spoon.shape", "valid: U, rectangular"});
  // Sizes against the case's largest particle: the trough wider than 3, the bed 2 top sizes deep.
  expect(chute_error(chute_with_particles("spoon: {profile: [[-0.2, 1.0], [0.5, 0.5]], width: 0.25}\n", 0.1)),
         {"equipment.transfer_chute.spoon.width", "3 times the largest particle", "valid: more than 0.3 m"});
  EXPECT_NO_THROW(generate(chute_with_particles("spoon: {profile: [[-0.2, 1.0], [0.5, 0.5]], width: 0.35}\n", 0.1)));
  expect(chute_error(chute_with_particles("rock_box: {height: 0.15}\n", 0.1)),
         {"equipment.transfer_chute.rock_box.height", "2 top sizes", "valid: at least 0.2 m"});
  expect(error_of("transfer_chute", "rock_box: {ledge_depth: 0.6}\n"), {"equipment.transfer_chute.rock_box.ledge_depth", "in front of the head pulley", "valid: ["});
  expect(error_of("transfer_chute", "rock_box: {ledge_depth: 0.1}\n"), {"equipment.transfer_chute.rock_box.ledge_depth", "behind the impact point"});
  expect(error_of("transfer_chute", "rock_box: {ledge_width: 0.9}\n"), {"equipment.transfer_chute.rock_box.ledge_width", "valid: [0.1, 0.7] m"});
  // A U trough needs walls as high as its half circle; walls that fold over on a sharp bend are refused.
  expect(error_of("transfer_chute", "spoon: {profile: [[-0.2, 1.0], [0.5, 0.5]], width: 0.6, depth: 0.2}\n"), {"spoon.depth", "half the width"});
  expect(error_of("transfer_chute", "spoon: {profile: [[-0.2, 1.2], [-0.2, 0.6], [0.4, 0.55]], shape: rectangular, depth: 0.7}\n"),
         {"spoon.depth", "fold over"});
}

/// Whether the triangle (a, b, c) holds the plan point (x, y) (edges included).
bool holds_in_plan(const Vec3& a, const Vec3& b, const Vec3& c, double x, double y) {
  const auto side = [&](const Vec3& p, const Vec3& q) { return (q.x() - p.x()) * (y - p.y()) - (q.y() - p.y()) * (x - p.x()); };
  const double s1 = side(a, b), s2 = side(b, c), s3 = side(c, a);
  const double tolerance = 1e-12;
  return (s1 >= -tolerance && s2 >= -tolerance && s3 >= -tolerance) || (s1 <= tolerance && s2 <= tolerance && s3 <= tolerance);
}

/// Whether a triangle of `mesh` lying at height z covers the plan point p.
bool deck_covers(const MeshWallSpec& mesh, double z, const Vec3& p) {
  for (const auto& t : mesh.triangles) {
    const Vec3 a = vertex(mesh, t[0]), b = vertex(mesh, t[1]), c = vertex(mesh, t[2]);
    if (std::abs(a.z() - z) > 1e-9 || std::abs(b.z() - z) > 1e-9 || std::abs(c.z() - z) > 1e-9) continue;
    if (holds_in_plan(a, b, c, p.x(), p.y())) return true;
  }
  return false;
}

// Mesh health of angled chutes (with a rock box, with a profile spoon): every triangle sound and
// short, every mesh wound one way (no edge run twice in the same direction), the plant inside the
// domain; the two boxes closed at the deck everywhere but the opening the stream falls through.
TEST(TransferChute, AngledChuteMeshesAreSoundAndClosedAtTheDeck) {
  for (const double angle : {30.0, 90.0, 135.0, 180.0})
    for (const std::string& shape : {std::string(""), std::string("U"), std::string("rectangular")}) {
      const std::string text = angled(angle, shape);
      SCOPED_TRACE(text);
      const Generated g = generate(make("transfer_chute", text));
      const TransferChuteLayout c = transfer_chute_layout(make("transfer_chute", text));
      for (const MeshWallSpec& m : g.meshes) {
        SCOPED_TRACE(m.name);
        std::map<std::pair<std::int32_t, std::int32_t>, int> edges;
        for (const auto& t : m.triangles) {
          for (const std::int32_t i : t) ASSERT_TRUE(i >= 0 && size_t(i) < m.vertices.size());
          const Vec3 a = vertex(m, t[0]), b = vertex(m, t[1]), d = vertex(m, t[2]);
          const double longest = std::max({(b - a).norm(), (d - b).norm(), (a - d).norm()});
          EXPECT_GT((b - a).cross(d - a).norm(), 1e-6 * longest * longest) << "degenerate triangle";
          if (m.name != "head_pulley") EXPECT_LT(longest, 0.3);  // the pulley's end caps are fans to its axis
          for (const Vec3& p : {a, b, d}) EXPECT_TRUE((p.array() >= g.domain_min.array()).all() && (p.array() <= g.domain_max.array()).all());
          for (int k = 0; k < 3; ++k) {
            const int runs = ++edges[std::make_pair(t[k], t[(k + 1) % 3])];
            EXPECT_EQ(runs, 1) << "an edge run twice the same way: normals flip";
          }
        }
      }
      // The deck: every plan point of one box outside the other is covered at join_z; the fall
      // line, where the stream comes down, is open.
      const MeshWallSpec& walls = mesh_named(g, "side_plates");
      const double half = 0.5 * c.chute_width;
      for (double x = c.side_x_min; x <= c.hood_box_x_max + 1e-9; x += 0.05)
        for (double y = -half; y <= half + 1e-9; y += 0.05) {
          const Vec3 local = to_local(c, Vec3(x, y, c.join_z));
          const bool in_spoon_box = local.x() > c.spoon_top_x - 1e-6 && local.x() < c.spoon_box_x_max + 1e-6 && std::abs(local.y()) < half + 1e-6;
          if (!in_spoon_box) EXPECT_TRUE(deck_covers(walls, c.join_z, Vec3(x, y, c.join_z))) << "hood box open at " << x << " " << y;
        }
      for (double x = c.spoon_top_x; x <= c.spoon_box_x_max + 1e-9; x += 0.05)
        for (double y = -half; y <= half + 1e-9; y += 0.05) {
          const Vec3 world = to_world(c, Vec3(x, y, c.join_z));
          const bool in_hood_box = world.x() > c.side_x_min - 1e-6 && world.x() < c.hood_box_x_max + 1e-6 && std::abs(world.y()) < half + 1e-6;
          if (!in_hood_box) EXPECT_TRUE(deck_covers(walls, c.join_z, world)) << "spoon box open at " << world.x() << " " << world.y();
        }
      EXPECT_FALSE(deck_covers(walls, c.join_z, Vec3(c.fall_x, 0, c.join_z))) << "the stream's way down is closed";
    }
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
  EXPECT_EQ(spec.sensors.size(), 5u);  // spoon_exit, belt_discharge, loading_zone, stream_chute, stream_belt

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
