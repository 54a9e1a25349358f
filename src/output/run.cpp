#include "output/run.h"

#include <fmt/format.h>
#include <fmt/ostream.h>
#include <omp.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>
#include <ostream>
#include <sstream>

#include "core/domain.h"
#include "core/step.h"
#include "output/checkpoint.h"
#include "output/results_hdf5.h"
#include "statistics/stream_profile.h"

namespace dem {

namespace {

std::atomic<int> stop_signal{0};
extern "C" void on_stop_signal(int signal) { stop_signal = signal; }

std::string format_duration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "?";
  const long s = std::lround(seconds);
  if (s >= 3600) return fmt::format("{}h{:02}m", s / 3600, (s % 3600) / 60);
  if (s >= 60) return fmt::format("{}m{:02}s", s / 60, s % 60);
  return fmt::format("{}s", s);
}

std::string scalars_csv(const Model& model, const std::vector<Scalars>& rows) {
  std::string out =
      "time_s,step,particles,kinetic_translation_J,kinetic_rotation_J,contacts,max_overlap_ratio,mean_overlap_ratio,"
      "dt_s,lost,inserted_mass_kg,removed_mass_kg";
  for (const OutletSpec& o : model.outlets) out += fmt::format(",outlet_{}_kg", o.name);
  for (const PlaneWall& w : model.planes) out += fmt::format(",wall_{}_normal_force_N", w.name);
  for (const MeshWall& m : model.meshes)
    out += fmt::format(",mesh_{0}_force_N,mesh_{0}_torque_Nm,mesh_{0}_power_W,mesh_{0}_fx_N,mesh_{0}_fy_N,mesh_{0}_fz_N,mesh_{0}_tx_Nm,"
                       "mesh_{0}_ty_Nm,mesh_{0}_tz_Nm", m.name);
  out += ",lost_mass_kg";
  for (const SensorSpec& s : model.sensors)
    out += s.kind == SensorSpec::Kind::plane ? fmt::format(",sensor_{0}_flow_kg_s,sensor_{0}_count_flow_1_s,sensor_{0}_vx_m_s,sensor_{0}_vy_m_s,sensor_{0}_vz_m_s", s.name)
                                             : fmt::format(",sensor_{0}_mass_kg,sensor_{0}_vx_m_s,sensor_{0}_vy_m_s,sensor_{0}_vz_m_s,sensor_{0}_offset_m", s.name);
  out += "\n";
  for (const Scalars& r : rows) {
    out += fmt::format("{:.9g},{},{},{:.9g},{:.9g},{},{:.6g},{:.6g},{:.6g},{},{:.9g},{:.9g}", r.time, r.step, r.particles,
                       r.kinetic_translation, r.kinetic_rotation, r.contacts, r.max_overlap_ratio, r.mean_overlap_ratio,
                       r.dt, r.lost, r.inserted_mass, r.removed_mass);
    for (double m : r.outlet_mass) out += fmt::format(",{:.9g}", m);
    for (double f : r.wall_normal_force) out += fmt::format(",{:.9g}", f);
    for (size_t m = 0; m < r.mesh_force.size(); ++m) {
      out += fmt::format(",{:.9g},{:.9g},{:.9g}", r.mesh_force[m], r.mesh_torque[m], r.mesh_power[m]);
      const std::array<double, 6> load = m < r.mesh_load.size() ? r.mesh_load[m] : std::array<double, 6>{};
      out += fmt::format(",{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g}", load[0], load[1], load[2], load[3], load[4], load[5]);
    }
    out += fmt::format(",{:.9g}", r.lost_mass);
    for (size_t k = 0; k < model.sensors.size() && k < r.sensors.size(); ++k) {
      const SensorReading& s = r.sensors[k];
      out += model.sensors[k].kind == SensorSpec::Kind::plane
                 ? fmt::format(",{:.9g},{:.9g},{:.9g},{:.9g},{:.9g}", s.flow, s.count_flow, s.vx, s.vy, s.vz)
                 : fmt::format(",{:.9g},{:.9g},{:.9g},{:.9g},{:.9g}", s.mass, s.vx, s.vy, s.vz, s.offset);
    }
    out += "\n";
  }
  return out;
}

/// Rows of an earlier scalars.csv up to `time` (a resumed run keeps what it had computed).
std::vector<Scalars> read_scalars(const Model& model, const std::string& path, double time) {
  std::vector<Scalars> rows;
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::stringstream fields(line);
    std::string cell;
    std::vector<double> v;
    while (std::getline(fields, cell, ',')) v.push_back(std::stod(cell));
    if (v.size() < 12 || v[0] > time + 1e-12) break;
    Scalars r;
    r.time = v[0], r.step = static_cast<std::int64_t>(v[1]), r.particles = static_cast<size_t>(v[2]);
    r.kinetic_translation = v[3], r.kinetic_rotation = v[4], r.contacts = static_cast<size_t>(v[5]);
    r.max_overlap_ratio = v[6], r.mean_overlap_ratio = v[7], r.dt = v[8], r.lost = static_cast<std::int64_t>(v[9]);
    r.inserted_mass = v[10], r.removed_mass = v[11];
    // Then one column per outlet, per wall, nine per mesh, lost mass, five per sensor.
    const size_t outlets = model.outlets.size(), walls = model.planes.size(), meshes = model.meshes.size();
    if (v.size() != 13 + outlets + walls + 9 * meshes + 5 * model.sensors.size()) break;
    size_t c = 12;
    for (size_t k = 0; k < outlets; ++k) r.outlet_mass.push_back(v[c++]);
    for (size_t k = 0; k < walls; ++k) r.wall_normal_force.push_back(v[c++]);
    for (size_t k = 0; k < meshes; ++k) {
      r.mesh_force.push_back(v[c++]);
      r.mesh_torque.push_back(v[c++]);
      r.mesh_power.push_back(v[c++]);
      r.mesh_load.push_back({v[c], v[c + 1], v[c + 2], v[c + 3], v[c + 4], v[c + 5]});
      c += 6;
    }
    r.lost_mass = v[c++];
    for (const SensorSpec& s : model.sensors) {
      SensorReading reading;
      if (s.kind == SensorSpec::Kind::plane) reading.flow = v[c], reading.count_flow = v[c + 1], reading.vx = v[c + 2], reading.vy = v[c + 3], reading.vz = v[c + 4];
      else reading.mass = v[c], reading.vx = v[c + 1], reading.vy = v[c + 2], reading.vz = v[c + 3], reading.offset = v[c + 4];
      c += 5;
      r.sensors.push_back(reading);
    }
    rows.push_back(r);
  }
  return rows;
}

/// A YAML double-quoted scalar of `text`.
std::string yaml_quoted(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

/// The run's set-up as YAML, so every result can be traced to its inputs (the command line that
/// started it included).
std::string run_info(const Model& model, const RunOptions& options, std::uint64_t run_id) {
  std::string out = fmt::format("software: demdesign {}\ncase: {}\nrun_id: {:016x}\n", DEMDESIGN_VERSION, model.source, run_id);
  if (!options.command_line.empty()) out += fmt::format("command_line: {}\n", yaml_quoted(options.command_line));
  out += fmt::format(
      "model_hash: {:016x}\ntime_step_s: {:.9g}\nmass_scaling: {:g}\n"
      "stiffness_scaling: {:g}\nrayleigh_time_s: {:.6g}\ncontact_time_s: {:.6g}\ncontact_law:\n",
      model.hash, model.dt, model.mass_scaling, model.stiffness_scaling,
      model.advice.rayleigh_time, model.advice.contact_time);
  for (const ActiveEffect& e : model.effects)
    out += fmt::format("  - {{stage: {}, model: {}, source: \"{}\"}}\n", stage_name(e.spec->stage),
                       e.spec->name, e.spec->citation);
  // Parcels (core/coarse_grain.h): the factor and what it did, beside the results they belong to.
  if (model.coarse_grain != 1.0) {
    out += fmt::format("coarse_grain: {:g}\ncoarse_grain_notes:\n", model.coarse_grain);
    for (const std::string& line : model.coarse_grain_report) out += fmt::format("  - {}\n", yaml_quoted(line));
  }
  out += "materials:\n";
  for (const Material& m : model.materials)
    out += fmt::format("  {}: {{density: {:.9g}, youngs_modulus: {:.9g}, poisson_ratio: {:g}}}\n", m.name, m.density,
                       m.youngs_modulus, m.poisson_ratio);
  return out;
}

/// A run id as the messages name it.
std::string run_id_text(std::uint64_t run_id) {
  return run_id ? fmt::format("run id {:016x}", run_id) : "a version that did not record run ids";
}

/// Why the checkpoint `from`, written by the run `checkpoint_run` at `state`, does not belong to
/// the results beside it in `out`; empty when it does. Checkpoints and run_info.yaml of versions
/// before run ids (both 0) belong together when the rows reach the checkpoint's time.
std::string foreign_checkpoint(const Model& model, const std::string& out, const std::string& from, std::uint64_t checkpoint_run,
                               const State& state, std::int64_t rows_every) {
  const std::string instead = "add --overwrite instead of --resume to start the run again, or resume in the folder the checkpoint was written in";
  const RunRecord record = read_run_record(out);
  if (!record.exists)
    return fmt::format("{}: no run_info.yaml beside it, so nothing tells which run's results it continues; resuming could splice two "
                       "runs' rows: {}", from, instead);
  if (checkpoint_run != record.run_id)
    return fmt::format("{}: the checkpoint belongs to another run ({}) than the results beside it ({}/run_info.yaml: {}); resuming "
                       "would splice the two runs' rows: {}", from, run_id_text(checkpoint_run), out, run_id_text(record.run_id), instead);
  if (checkpoint_run == 0) {
    const std::vector<Scalars> rows = read_scalars(model, out + "/scalars.csv", std::numeric_limits<double>::infinity());
    const double reached = rows.empty() ? -std::numeric_limits<double>::infinity() : rows.back().time;
    if (reached < state.time - static_cast<double>(rows_every) * model.dt * (1 + 1e-9) - 1e-12)
      return fmt::format("{}: the rows beside it ({}/scalars.csv) {}, before the checkpoint's t = {:.6g} s: they are another run's; {}",
                         from, out, rows.empty() ? "are missing" : fmt::format("end at t = {:.6g} s", reached), state.time, instead);
  }
  return "";
}

FrameWriter make_frame_writer(const Model& model, const std::string& directory) {
  std::vector<std::string> names;
  for (const Material& m : model.materials) names.push_back(m.name);
  std::vector<std::pair<std::string, std::string>> attributes = {{"software", fmt::format("demdesign {}", DEMDESIGN_VERSION)},
                                                                  {"case", model.source},
                                                                  {"mass_scaling", fmt::format("{:g}", model.mass_scaling)},
                                                                  {"stiffness_scaling", fmt::format("{:g}", model.stiffness_scaling)},
                                                                  {"time_step_s", fmt::format("{:.9g}", model.dt)}};
  // Parcels' frames say so: their spheres are F times the real particles (core/coarse_grain.h).
  if (model.coarse_grain != 1.0) attributes.emplace_back("coarse_grain", fmt::format("{:g}", model.coarse_grain));
  return FrameWriter(directory, names, std::move(attributes));
}

/// Fields mean_traction_x_Pa, _y_Pa, _z_Pa of a mesh: the particles' force per area over the
/// records' interval (per_area_rate), kept in the mesh's own frame and turned here by its pose
/// at the end of the run, the pose the vertices are written in (the identity for a mesh without
/// motion).
template <typename PerAreaRate>
void add_mean_traction(MeshFieldSet& set, const TriangleRecords& r, const Pose& pose, PerAreaRate per_area_rate) {
  const std::vector<double> local[3] = {per_area_rate(r.force_impulse_x), per_area_rate(r.force_impulse_y), per_area_rate(r.force_impulse_z)};
  std::vector<double> world[3];
  for (size_t t = 0; t < local[0].size() && t < local[1].size() && t < local[2].size(); ++t) {
    const Eigen::Vector3d v = pose.rotation * Eigen::Vector3d(local[0][t], local[1][t], local[2][t]);
    for (int a = 0; a < 3; ++a) world[a].push_back(v[a]);
  }
  set.fields.push_back({"mean_traction_x_Pa", std::move(world[0])});
  set.fields.push_back({"mean_traction_y_Pa", std::move(world[1])});
  set.fields.push_back({"mean_traction_z_Pa", std::move(world[2])});
}

/// The wear inputs of every mesh triangle, as run totals and per-area rates over the run.
void write_mesh_records(const Model& model, const State& s, const std::string& out) {
  std::vector<MeshFieldSet> sets;
  const double duration = std::max(s.time - model.output.records_from, 1e-30);  // [s] the records' interval
  for (size_t m = 0; m < model.meshes.size(); ++m) {
    const MeshWall& mesh = model.meshes[m];
    MeshFieldSet set;
    set.name = mesh.name;
    set.triangles = mesh.surface->triangles;
    const Pose pose = mesh.motion.pose(s.time);
    for (const auto& v : mesh.surface->vertices) {
      const Eigen::Vector3d w = pose.rotation * Eigen::Vector3d(v[0], v[1], v[2]) + pose.translation;
      set.vertices.push_back({w.x(), w.y(), w.z()});
    }
    const TriangleRecords& r = s.records[m];
    const auto& area = mesh.surface->areas;
    auto per_area_rate = [&](const std::vector<double>& total) {
      std::vector<double> rate(total.size());
      for (size_t t = 0; t < total.size(); ++t) rate[t] = area[t] > 0 ? total[t] / (area[t] * duration) : 0.0;
      return rate;
    };
    set.fields = {{"mean_pressure_Pa", per_area_rate(r.normal_impulse)},
                  {"mean_shear_stress_Pa", per_area_rate(r.shear_impulse)},
                  {"shear_work_rate_W_per_m2", per_area_rate(r.shear_work)},
                  {"impact_energy_rate_W_per_m2", per_area_rate(r.impact_energy)},
                  {"impacts_per_s_m2", per_area_rate(r.impacts)},
                  {"shear_work_J", r.shear_work},
                  {"impact_energy_J", r.impact_energy},
                  {"impacts", r.impacts}};
    add_mean_traction(set, r, pose, per_area_rate);
    sets.push_back(std::move(set));
  }
  write_mesh_fields(out, sets, s.time);
}

}  // namespace

void write_frame(FrameWriter& writer, const State& s, const FrameShare* share) {
  // Orientation per sphere: its body's, identity for free spheres.
  const size_t n = s.owned();
  std::vector<double> qw(n, 1.0), qx(n, 0.0), qy(n, 0.0), qz(n, 0.0);
  for (size_t p = 0; p < n; ++p) {
    const std::int32_t b = s.body[p];
    if (b < 0) continue;
    qw[p] = s.bodies.qw[b], qx[p] = s.bodies.qx[b], qy[p] = s.bodies.qy[b], qz[p] = s.bodies.qz[b];
  }
  ParticleFrame frame;
  frame.time = s.time, frame.step = s.step, frame.count = n;
  frame.id = s.id.data();
  frame.x = s.x.data(), frame.y = s.y.data(), frame.z = s.z.data();
  frame.vx = s.vx.data(), frame.vy = s.vy.data(), frame.vz = s.vz.data();
  frame.wx = s.wx.data(), frame.wy = s.wy.data(), frame.wz = s.wz.data();
  frame.radius = s.radius.data(), frame.material = s.material.data(), frame.clump = s.body.data();
  frame.qw = qw.data(), frame.qx = qx.data(), frame.qy = qy.data(), frame.qz = qz.data();
  if (share) writer.write_frame(frame, *share);
  else writer.write_frame(frame);
}


void write_file_atomically(const std::string& path, const std::string& content) {
  const std::filesystem::path target(path);
  if (target.has_parent_path()) std::filesystem::create_directories(target.parent_path());
  const std::string temporary = path + ".part";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out << content;
    out.flush();
    out.close();
    if (!out) {
      std::error_code ignored;
      std::filesystem::remove(temporary, ignored);
      throw std::runtime_error(fmt::format("{}: cannot write {} bytes (disk full, file size limit or no permission?); "
                                           "the previous {} is kept unchanged",
                                           path, content.size(), target.filename().string()));
    }
  }
  std::error_code error;
  std::filesystem::rename(temporary, target, error);
  if (error) {
    std::filesystem::remove(temporary, error);
    throw std::runtime_error(fmt::format("{}: cannot replace it ({}); the previous version is kept", path, error.message()));
  }
}

/// Particles placed wholly behind a one-sided plane wall, and inlets whose whole region lies
/// behind one: such particles never meet the wall they were meant to rest on and fall until they
/// leave the domain (or forever, without one). One warning line each.
std::vector<std::string> particles_behind_walls(const Model& model, const State& state) {
  std::vector<std::string> out;
  for (const PlaneWall& w : model.planes) {
    if (w.shape != PlaneWall::Shape::plane) continue;
    const auto side = [&](double x, double y, double z) {
      return (x - w.point[0]) * w.normal[0] + (y - w.point[1]) * w.normal[1] + (z - w.point[2]) * w.normal[2];
    };
    std::int64_t behind = 0, first = -1;
    for (std::size_t i = 0; i < state.size(); ++i)
      if (state.attached[i] < 0 && side(state.x[i], state.y[i], state.z[i]) < -state.radius[i]) {
        if (first < 0) first = state.id[i];
        ++behind;
      }
    if (behind > 0)
      out.push_back(fmt::format("{} particle{} (the first with id {}) start{} wholly behind plane wall '{}' (its normal points to where particles "
                                "belong): {} never touch it and fall through; move them to its side or turn its normal",
                                behind, behind == 1 ? "" : "s", first, behind == 1 ? "s" : "", w.name, behind == 1 ? "it will" : "they will"));
    for (const Inlet& inlet : model.inlets) {
      const Vec3& a = inlet.spec.region_min;
      const Vec3& b = inlet.spec.region_max;
      bool all_behind = true;
      for (int corner = 0; corner < 8 && all_behind; ++corner)
        all_behind = side(corner & 1 ? b.x() : a.x(), corner & 2 ? b.y() : a.y(), corner & 4 ? b.z() : a.z()) < 0;
      if (all_behind)
        out.push_back(fmt::format("inlet '{}' lies wholly behind plane wall '{}' (its normal points to where particles belong): what it "
                                  "inserts never touches that wall",
                                  inlet.spec.name, w.name));
    }
  }
  return out;
}

void print_setup(const Model& model, const State& state, std::ostream& log) {
  fmt::print(log, "demdesign {}: {}{}\n", DEMDESIGN_VERSION, model.source, model.title.empty() ? "" : " - " + model.title);
  fmt::print(log, "  {} spheres ({} clumps), {} materials, {} plane walls, {} inlets, {} outlets, {} threads\n",
             state.size(), state.bodies.size(), model.materials.size(), model.planes.size(), model.inlets.size(),
             model.outlets.size(), omp_get_max_threads());
  std::string law;
  for (const ActiveEffect& e : model.effects)
    law += fmt::format("{}{}: {}", law.empty() ? "" : ", ", stage_name(e.spec->stage), e.spec->name);
  fmt::print(log, "  contact law: {}\n", law);
  for (const ActiveEffect& e : model.effects) fmt::print(log, "    {}: {}\n", e.spec->name, e.spec->citation);
  fmt::print(log, "{}\n", model.advice.report);
  if (model.mass_scaling != 1.0 || model.stiffness_scaling != 1.0)
    fmt::print(log, "  SCALING: particle density x {:g} (mass scaling), particle Young's modulus x {:g} (reduced "
                    "stiffness); both are written with every result\n",
               model.mass_scaling, model.stiffness_scaling);
  else
    fmt::print(log, "  scaling: none (mass x 1, stiffness x 1)\n");
  // Coarse graining (core/coarse_grain.h): F, the parcels, the parameters scaled, what the results are.
  for (const std::string& line : model.coarse_grain_report) fmt::print(log, "  {}\n", line);
  if (model.periodic())
    fmt::print(log, "  periodic: {}{}{} (periods {:g} {:g} {:g} m)\n", model.period[0] > 0 ? "x" : "", model.period[1] > 0 ? "y" : "",
               model.period[2] > 0 ? "z" : "", model.period[0], model.period[1], model.period[2]);
  fmt::print(log, "  neighbour skin {:.3g} m, interaction range {:.3g} m\n", model.skin, model.interaction_range);
  for (const std::string& note : model.notes) fmt::print(log, "  note: {}\n", note);
  for (const std::string& warning : particles_behind_walls(model, state)) fmt::print(log, "  WARNING: {}\n", warning);
}

namespace {

using Clock = std::chrono::steady_clock;
using SignalHandler = void (*)(int);  // what std::signal returns

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

/// What run() is given and what it decides before its first step.
struct RunSetup {
  const Model& model;
  State& state;
  Workspace& work;
  const RunOptions& options;
  std::ostream& log;
  std::string out;        // the output folder
  double duration;        // [s] to run
  std::int64_t end_step;  // the step that reaches `duration`
  // Under domain decomposition every rank steps its share with the domain's model; the ranks
  // write each frame together (options.share_frame) or the root gathers the whole state for it,
  // and the root gathers it for images and at the end and writes the rest as one process would.
  Domain* domain;
  bool writer;            // this process writes the results: the only one, or the root
  bool collective;        // the ranks write each frame together
  const Model& stepped;   // the model this process steps
  std::uint64_t run_id;   // in run_info.yaml and every checkpoint
};

/// The whole state for results: the state itself, or (domain) the root's gathered copy with its
/// lists rebuilt (and, for the caller at the end, a copy with this instant's contact forces),
/// gathered for frames unless the ranks write them together, for rendered frames and at the end.
struct WholeResults {
  std::optional<WholeState> whole;
  const State* state;     // positions, counters, histories
  const Workspace* work;
  bool gathered;          // on every rank alike: whether gather_whole has run
};

/// Counts of the whole run, as of the last row of scalars (every rank's under domain decomposition).
struct RowTotals {
  std::int64_t lost;      // particles lost, every rank's
  double particles;       // particles in the whole run, for the progress line
};

/// Which steps end the run, record a row of scalars, write a frame or a checkpoint, and check.
struct Schedule {
  std::int64_t first_step;
  std::int64_t last_step;
  std::int64_t total;             // steps to run
  std::int64_t every;             // steps between rows of scalars
  std::int64_t frame_every;       // steps between frames
  std::int64_t checkpoint_every;  // steps between checkpoints; 0: none by step count
  std::int64_t check_every;       // steps between numerical checks
};

/// What watches the run for trouble and for events, and what it has told of them.
struct Watches {
  EnergyWatch energy;
  // First arrivals to the step (events.h); one process only: under domain decomposition each rank
  // holds a share of the particles.
  EventWatch events;
  double last_check;           // [s] the time of the last check
  std::int64_t lost_reported;  // particles lost as last told
  std::int64_t warnings;       // numerical trouble warned of, the run going on
};

/// The particle frames the run writes.
struct Outputs {
  std::optional<FrameWriter> frames;
  double frame_seconds = 0;  // [s] this rank's time writing frames
};

/// The step loop's start: the signal handlers it replaced and the wall clock's reading.
struct LoopStart {
  SignalHandler previous_int;
  SignalHandler previous_term;
  Clock::time_point start;
};

/// What the step loop and the run's end share: the setup and the parts built before the loop.
struct RunParts {
  const RunSetup& setup;
  RunSummary& summary;
  Watches& watches;
  WholeResults& results;
  RowTotals& totals;
  const Schedule& schedule;
  Outputs& outputs;
  const LoopStart& loop_start;
};

/// Where the run writes, how far it runs and, under domain decomposition, which process writes.
RunSetup plan_run(const Model& model, State& state, Workspace& work, const RunOptions& options, std::ostream& log,
                  RunSummary& summary) {
  summary.output_directory = options.output_directory.empty() ? model.output.directory : options.output_directory;
  const double duration = options.duration >= 0 ? options.duration : model.duration;
  if (!(duration >= 0) || duration / model.dt > 1e15)
    throw CaseError(fmt::format("duration {:g} s is not a time this run can reach ({:.3g} steps of {:.3g} s); valid: 0 to 1e6 s", duration,
                                duration / model.dt, model.dt));
  const std::int64_t end_step = static_cast<std::int64_t>(std::ceil(duration / model.dt - 1e-9));
  Domain* domain = options.domain;
  const bool writer = domain == nullptr || domain->root();
  const bool collective = domain != nullptr && static_cast<bool>(options.share_frame);
  const Model& stepped = domain ? domain->local_model() : model;
  work.domain = domain;
  return RunSetup{model, state, work, options, log, summary.output_directory, duration, end_step, domain, writer, collective, stepped, 0};
}

/// A refusal on the root stops every rank (the others would wait for it forever).
void stop_if_refused(const RunSetup& s, const std::string& refused) {
  if (s.domain ? s.domain->any(!refused.empty()) : !refused.empty())
    throw CaseError(!refused.empty() ? refused : "rank 0 refused the output folder (its message is on standard error)");
}

/// The output folder, claimed by the process that writes the results: refused when it holds
/// another run's results (unless resumed or overwritten) or a file of the run's names that no
/// run wrote; locked until the caller lets go of the summary (run_folder.h).
void claim_folder(const RunSetup& s, RunSummary& summary) {
  std::string refused;
  if (s.writer && s.options.folder) {
    summary.folder = s.options.folder;
  } else if (s.writer) {
    try {
      std::vector<std::string> names = run_output_names();
      names.insert(names.end(), s.options.caller_outputs.begin(), s.options.caller_outputs.end());
      const FolderUse use = s.options.resume ? FolderUse::resume : s.options.overwrite ? FolderUse::overwrite : FolderUse::fresh;
      summary.folder = std::make_shared<RunFolder>(s.out, use, names, s.log);
    } catch (const std::exception& e) {
      refused = e.what();
    }
  }
  stop_if_refused(s, refused);
}

/// The state, run id, rows and events of the run in OUT, from its checkpoint; a run that reached
/// its end is left as it is (summary.already_complete).
void resume_from_checkpoint(RunSetup& s, RunSummary& summary) {
  // A run that reached its end has nothing to resume: it is said, not rewound to its last checkpoint.
  const RunRecord record = s.writer ? read_run_record(s.out) : RunRecord{};
  bool complete = s.writer && record.completed && record.step >= s.end_step;
  if (s.domain) complete = s.domain->any(complete);
  if (complete) {
    if (s.writer)
      fmt::print(s.log, "  {}: the run is complete (t = {:.6g} s, step {}; run_info.yaml): nothing to resume. To run it again from the "
                        "start, use --overwrite instead of --resume\n", s.out, record.time, record.step);
    summary.already_complete = true;
    return;
  }
  std::string from;
  s.state = load_resumable(s.out, s.model, &from, &s.run_id);
  // The checkpoint must belong to the rows beside it, or the resumed run would splice two runs.
  const std::int64_t rows_every =
      s.model.output.scalars_every > 0 ? s.model.output.scalars_every : std::max<std::int64_t>(1, s.end_step / 200);
  stop_if_refused(s, s.writer ? foreign_checkpoint(s.model, s.out, from, s.run_id, s.state, rows_every) : "");
  if (s.writer) summary.scalars = read_scalars(s.model, s.out + "/scalars.csv", s.state.time);
  if (s.writer) fmt::print(s.log, "  resumed from {} at t = {:.6g} s (step {})\n", from, s.state.time, s.state.step);
}

/// The energy and event watches, from the state the run starts from (a resumed run's events kept).
Watches watch_run(const RunSetup& s) {
  Watches w{EnergyWatch(s.model, s.state, s.model.energy_rise_limit), EventWatch(s.model), s.state.time, 0, 0};
  if (s.options.resume && s.writer) w.events.restore(read_events(s.out + "/events.csv", s.state.time));
  return w;
}

/// Under domain decomposition, the whole state gathered on the root for results (collective).
void gather_whole(const RunSetup& s, WholeResults& r) {
  if (!s.domain) return;
  r.gathered = true;
  State gathered_state = s.domain->gather(s.state);
  if (!s.writer) return;
  r.whole = ready_for_results(s.model, std::move(gathered_state));
  r.state = &r.whole->state, r.work = &r.whole->work;
}

/// A row of scalars (collective under domain decomposition): each rank measures its own
/// particles and the contacts it lists, the parts are summed over the ranks and the root
/// finishes the row; no rank gathers the state for it (diagnostics.h).
Scalars measure_row(const RunSetup& s, RowTotals& totals) {
  if (!s.domain) return measure(s.model, s.state, s.work);
  ScalarParts parts = measure_parts(s.stepped, s.state, s.work);
  s.domain->sum(parts.sums);
  parts.max_overlap_ratio = s.domain->max(parts.max_overlap_ratio);
  Scalars row = finish_scalars(s.model, s.state, parts);
  totals.lost = row.lost;
  return row;
}

/// A row of scalars measured and, by the process that writes the results, kept; its bins added
/// to the stream profiles on every rank alike, and then dropped from the row (the profiles hold
/// them; a run of many rows keeps no bins per row).
void add_row(const RunSetup& s, RunSummary& summary, RowTotals& totals) {
  Scalars row = measure_row(s, totals);
  s.state.mesh_loads.restart_interval();
  accumulate_stream_profiles(s.model, row, s.state);
  for (SensorReading& reading : row.sensors) reading.bin_mass = std::vector<double>(), reading.bin_momentum = std::vector<double>();
  totals.particles = static_cast<double>(row.particles);
  if (s.writer) summary.scalars.push_back(std::move(row));
}

/// Where the run ends (options.max_steps may end it early) and how often it records, writes and checks.
Schedule schedule_steps(const RunSetup& s) {
  const Model& model = s.model;
  const std::int64_t first_step = s.state.step;
  std::int64_t last_step = s.end_step;
  if (s.options.max_steps >= 0) last_step = std::min(last_step, first_step + s.options.max_steps);
  const std::int64_t total = std::max<std::int64_t>(last_step - first_step, 0);
  const std::int64_t every =
      model.output.scalars_every > 0 ? model.output.scalars_every : std::max<std::int64_t>(1, s.end_step / 200);
  const std::int64_t frame_every = std::max<std::int64_t>(
      1, static_cast<std::int64_t>(std::llround((model.output.frames_every > 0 ? model.output.frames_every : s.duration / 20) / model.dt)));
  const std::int64_t checkpoint_every =
      model.output.checkpoint_every > 0 ? std::max<std::int64_t>(1, std::llround(model.output.checkpoint_every / model.dt)) : 0;
  // Numerical trouble: checked every few steps (cheap next to a step), so it is caught within
  // a few steps of its start, not at the next row of scalars.
  const std::int64_t check_every = std::min<std::int64_t>(every, 10);
  return Schedule{first_step, last_step, total, every, frame_every, checkpoint_every, check_every};
}

/// A particle frame: this rank's share written by every rank together, or the whole state (or,
/// in one process, the state) by this process; its time counted in frame_seconds.
void write_frame_now(const RunSetup& s, Outputs& o, const State& whole_or_mine) {
  const auto begun = std::chrono::steady_clock::now();
  if (s.collective) {
    const FrameShare share = s.options.share_frame(s.state.owned());
    write_frame(*o.frames, s.state, &share);
  } else {
    write_frame(*o.frames, whole_or_mine);
  }
  o.frame_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - begun).count();
}

/// Just before the first write: an earlier run's files go (overwrite) and the folder is listed.
void begin_writing(const RunSetup& s, const RunSummary& summary) {
  std::string failed;
  if (s.writer) {
    try {
      summary.folder->begin(s.log);
    } catch (const std::exception& e) {
      failed = e.what();
    }
  }
  stop_if_refused(s, failed);
}

/// The run record of the run begun and its frames: a new run's with its first frame, a resumed
/// run's adopted.
void open_outputs(const RunSetup& s, const WholeResults& results, Outputs& o) {
  if (s.writer) write_file_atomically(s.out + "/run_info.yaml", run_info(s.model, s.options, s.run_id));
  o.frames.emplace(make_frame_writer(s.model, s.out));
  if (s.options.resume && s.writer) o.frames->adopt_existing();
  else if (!s.options.resume) write_frame_now(s, o, *results.state);
}

/// Trouble present from the start (particles created overlapping): told before the first step.
/// With frames written together no rank holds the whole state: each checks its share.
void check_start(const RunSetup& s, const WholeResults& results) {
  std::optional<NumericalError> found;
  try {
    if (s.collective) check_numerics(s.stepped, s.state, s.work, s.model.max_overlap_ratio);
    else check_numerics(s.model, *results.state, *results.work, s.model.max_overlap_ratio);
  } catch (const NumericalError& e) {
    found = e;
  }
  if (s.collective && s.domain->any(found.has_value()) && !found)
    found = NumericalError(fmt::format("t = {:.6g} s: another rank found numerical trouble (its message is on standard error)", s.state.time));
  if (found) {
    if (s.model.stop_on_trouble) throw *found;
    fmt::print(s.writer ? s.log : std::cerr, "  WARNING (numerical_trouble: warn, the run goes on): {}\n", found->what());
  }
}

/// The step loop begun: SIGINT and SIGTERM caught (they stop the run at a step, with a
/// checkpoint), an energy check that cannot be used told, losses counted from here, the wall
/// clock read.
LoopStart start_loop(const RunSetup& s, Watches& w) {
  stop_signal = 0;
  const SignalHandler previous_int = std::signal(SIGINT, on_stop_signal);
  const SignalHandler previous_term = std::signal(SIGTERM, on_stop_signal);
  if (!w.energy.active() && s.writer) fmt::print(s.log, "  energy check: off ({})\n", w.energy.source());
  w.lost_reported = s.state.lost, w.warnings = 0;
  return LoopStart{previous_int, previous_term, Clock::now()};
}

void restore_signals(const LoopStart& loop_start) {
  std::signal(SIGINT, loop_start.previous_int);
  std::signal(SIGTERM, loop_start.previous_term);
}

/// The rows so far, the events and the ParaView script (at checkpoints, on trouble, at the end).
void write_tables(const RunParts& parts) {
  const std::string& out = parts.setup.out;
  write_file_atomically(out + "/scalars.csv", scalars_csv(parts.setup.model, parts.summary.scalars));
  write_file_atomically(out + "/events.csv", events_csv(parts.watches.events.fired()));
  if (parts.outputs.frames) write_paraview_script(out);
}

/// Numerical trouble found by a check: the run stops with RunStopped (numerical_trouble: stop)
/// or goes on with a warning (the first 20 told).
void on_trouble(RunParts& parts, const NumericalError& e) {
  const RunSetup& s = parts.setup;
  RunSummary& summary = parts.summary;
  if (s.model.stop_on_trouble) {
    // Keep what was computed: the rows so far and a run record that says why it ended (the last
    // checkpoint stays as it was).
    summary.stopped = fmt::format("numerical trouble: {}", e.what());
    summary.steps = s.state.step - parts.schedule.first_step;
    summary.events = parts.watches.events.fired();
    summary.wall_seconds = std::chrono::duration<double>(Clock::now() - parts.loop_start.start).count();
    if (s.options.write_files && s.writer) {
      try {
        write_tables(parts);
        write_file_atomically(s.out + "/run_info.yaml", run_info(s.model, s.options, s.run_id) +
                                                            fmt::format("end:\n  completed: false\n  time_s: {:.17g}\n  step: {}\n  stopped: {}\n",
                                                                        s.state.time, s.state.step, yaml_quoted(summary.stopped)));
      } catch (const std::exception&) {
      }
    }
    restore_signals(parts.loop_start);
    throw RunStopped(e, summary);
  }
  if (parts.watches.warnings++ < 20) fmt::print(s.writer ? s.log : std::cerr, "  WARNING (numerical_trouble: warn, the run goes on): {}\n", e.what());
}

/// Particles that left the domain, told at the first loss and then at each tenfold.
void tell_losses(RunParts& parts) {
  const RunSetup& s = parts.setup;
  const State& state = s.state;
  Domain* const domain = s.domain;
  std::int64_t& lost_reported = parts.watches.lost_reported;
  // Under domain decomposition the count is every rank's as of the last row, and the
  // particle named is the last the root knows of (its own, or of the last gathered state).
  const std::int64_t lost_now = domain ? parts.totals.lost : state.lost;
  if (s.writer && lost_now > lost_reported) {
    const auto& p = state.lost > 0 || !domain ? state.last_lost : parts.results.state->last_lost;
    const bool named = state.lost > 0 || (domain && parts.results.state->lost > 0);
    // The first loss, then each tenfold: a leak is told, not repeated every step.
    if (lost_reported == 0 || lost_now >= 10 * lost_reported) {
      fmt::print(s.log, "  WARNING: t = {:.6g} s: {} particles have left the domain (simulation.domain) and were removed; {}Likely "
                        "causes: an opening in the walls, a wall that does not reach the domain's edge, or a time step so "
                        "large that particles pass through a wall\n",
                 state.time, lost_now,
                 named ? fmt::format("the last, particle {}, at [{:.4g}, {:.4g}, {:.4g}] m moving at [{:.3g}, {:.3g}, {:.3g}] m/s. ", p.id,
                                     p.x, p.y, p.z, p.vx, p.vy, p.vz)
                       : "");
      lost_reported = lost_now;
    }
  }
}

/// The checks at a step that checks: numerical trouble, first arrivals, particles lost.
void check_step(RunParts& parts) {
  const RunSetup& s = parts.setup;
  const Model& model = s.model;
  const State& state = s.state;
  Domain* const domain = s.domain;
  Watches& w = parts.watches;
  // Under domain decomposition every rank's energy, summed before any rank may throw; the
  // root judges it.
  const double energy_total = domain && w.energy.active() ? domain->sum(mechanical_energy(s.stepped, state)) : 0.0;
  std::optional<NumericalError> found;
  try {
    check_numerics(s.stepped, state, s.work, model.max_overlap_ratio);
    if (!domain) w.energy.check(model, state);
    else if (s.writer) w.energy.check(model, state, energy_total);
  } catch (const NumericalError& e) {
    found = e;
  }
  if (domain && domain->any(found.has_value()) && !found)
    found = NumericalError(fmt::format("t = {:.6g} s: another rank found numerical trouble (its message is on standard error)", state.time));
  if (found) on_trouble(parts, *found);
  if (!domain && w.events.check(s.stepped, state, w.last_check) && s.writer && s.options.progress)
    for (auto e = w.events.fired().rbegin(); e != w.events.fired().rend() && e->step > state.step - parts.schedule.check_every; ++e)
      fmt::print(s.log, "  t = {:.6g} s (step {}): {} (particle {})\n", e->time, e->step, e->what, e->particle);
  w.last_check = state.time;
  tell_losses(parts);
}

/// A checkpoint with the tables: every rank's share committed by the root (domain), or the whole state.
void write_checkpoint(RunParts& parts) {
  const RunSetup& s = parts.setup;
  const State& state = s.state;
  Domain* const domain = s.domain;
  if (domain) {
    // Every rank's share on disk before the root names the step: a failed write on any rank
    // stops every rank, the last complete checkpoint kept.
    std::string failed;
    try {
      save_checkpoint_share(s.out, s.model, state.step, domain->rank(), domain->ranks(), pack_share(state, s.stepped.history_width));
    } catch (const std::exception& e) {
      failed = e.what();
    }
    if (domain->any(!failed.empty()))
      throw std::runtime_error(failed.empty() ? fmt::format("t = {:.6g} s: another rank could not write its checkpoint share (its log says why)", state.time)
                                              : failed);
    if (s.writer) {
      commit_checkpoint_shares(s.out, s.model, state, s.run_id);
      write_tables(parts);
    }
  } else if (s.writer) {
    save_whole_checkpoint(s.out, s.model, *parts.results.state, s.run_id);
    write_tables(parts);
  }
}

/// The progress line: simulated time, particles, speed and the time left.
void report_progress(const RunParts& parts, Clock::time_point now, std::int64_t particle_steps) {
  const RunSetup& s = parts.setup;
  const State& state = s.state;
  const Schedule& schedule = parts.schedule;
  const double elapsed = std::chrono::duration<double>(now - parts.loop_start.start).count();
  const std::int64_t done = state.step - schedule.first_step;
  const double left = elapsed / static_cast<double>(done) * static_cast<double>(schedule.last_step - state.step);
  fmt::print(s.log, "  t = {:.4g} / {:.4g} s ({:.0f} %), {} particles, {:.3g} particle-steps/s, time left {}\n",
             state.time, s.duration, 100.0 * done / std::max<std::int64_t>(schedule.total, 1),
             s.domain ? static_cast<std::size_t>(parts.totals.particles) : state.size(), particle_steps / elapsed,
             format_duration(left));
  s.log.flush();
}

// Steps until the next one that checks, records or writes run as one advance() (each closing
// kick gives the next step's drift, step.h); under domain decomposition one at a time.
std::int64_t steps_to_next_event(const Schedule& schedule, const State& state) {
  std::int64_t steps = schedule.last_step - state.step;
  for (const std::int64_t every_n : {schedule.check_every, schedule.every, schedule.frame_every, schedule.checkpoint_every})
    if (every_n > 0) steps = std::min(steps, every_n - state.step % every_n);
  return std::max<std::int64_t>(steps, 1);
}

/// The steps to the end, or to a stop by a signal: after each run of steps, what is due at the
/// step it reached. Returns the particle-steps run (every rank's under domain decomposition).
std::int64_t run_steps(RunParts& parts) {
  const RunSetup& s = parts.setup;
  const Model& model = s.model;
  const RunOptions& options = s.options;
  State& state = s.state;
  Domain* const domain = s.domain;
  const bool writer = s.writer, collective = s.collective;
  const Schedule schedule = parts.schedule;  // a copy: the loop reads it at every step
  const auto start = parts.loop_start.start;
  auto last_progress = start;
  // What a kill (SIGKILL, the OOM killer, a power cut) may cost: the rows since the last save
  // (output.rows_seconds of wall time) and the computing since the last checkpoint
  // (output.checkpoint_seconds, or checkpoint_every).
  auto last_rows_saved = start, last_checkpoint = start;
  std::int64_t particle_steps = 0;
  std::int64_t loop_frames = 0;  // frames written in the loop; on_frame follows every render_every-th
  while (state.step < schedule.last_step) {
    if (domain) {
      step(s.stepped, state, s.work);
      particle_steps += static_cast<std::int64_t>(parts.totals.particles);
    } else {
      particle_steps += advance(s.stepped, state, s.work, steps_to_next_event(schedule, state));
    }
    const bool last = state.step == schedule.last_step;
    const bool check_due = state.step % schedule.check_every == 0 || last;
    // A signal stops every rank at the same step.
    const bool stopping = domain ? check_due && domain->any(stop_signal != 0) : stop_signal != 0;
    const bool scalars_due = state.step % schedule.every == 0 || last;
    const bool frame_due = options.write_files && (state.step % schedule.frame_every == 0 || last);
    // A checkpoint on the wall clock: the root's clock decides, for every rank at the same step.
    bool checkpoint_timed = options.write_files && model.output.checkpoint_seconds > 0 && !last &&
                            (!domain || check_due) && writer && seconds_since(last_checkpoint) >= model.output.checkpoint_seconds;
    if (domain && check_due) checkpoint_timed = domain->any(checkpoint_timed);
    const bool checkpoint_due =
        options.write_files && ((schedule.checkpoint_every && state.step % schedule.checkpoint_every == 0) || stopping || checkpoint_timed);
    if (checkpoint_due) last_checkpoint = Clock::now(), last_rows_saved = last_checkpoint;
    const bool render_due = frame_due && options.on_frame &&
                            (last || (model.output.render_every > 0 && loop_frames % model.output.render_every == 0));
    if (frame_due) ++loop_frames;
    // A checkpoint needs no gather: each rank writes its share (checkpoint.h); nor does a frame
    // the ranks write together.
    if (domain && ((frame_due && !collective) || render_due || last || stopping)) gather_whole(s, parts.results);
    if (check_due) check_step(parts);
    if (scalars_due) {
      add_row(s, parts.summary, parts.totals);
      if (writer && options.write_files && !checkpoint_due && !last && model.output.rows_seconds > 0 &&
          seconds_since(last_rows_saved) >= model.output.rows_seconds) {
        write_tables(parts);
        last_rows_saved = Clock::now();
      }
    }
    if (parts.outputs.frames && frame_due) {
      const WholeResults& results = parts.results;
      write_frame_now(s, parts.outputs, *results.state);
      if (render_due && writer) options.on_frame(model, *results.state, *results.work, s.out, last);
    }
    if (checkpoint_due) write_checkpoint(parts);
    if (stopping) {
      parts.summary.stopped = fmt::format("stopped by signal {} at t = {:.6g} s; checkpoint written, resume with --resume", int(stop_signal), state.time);
      if (writer)
        fmt::print(s.log, "  stopped by signal {} at t = {:.6g} s; checkpoint written, resume with --resume\n", int(stop_signal),
                   state.time);
      break;
    }
    const auto now = Clock::now();
    if (writer && options.progress && std::chrono::duration<double>(now - last_progress).count() >= model.output.progress_seconds) {
      last_progress = now;
      report_progress(parts, now, particle_steps);
    }
  }
  return particle_steps;
}

/// The loop left: the signal handlers put back, the whole state gathered if no step was, and the
/// summary's counts.
void end_loop(RunParts& parts, std::int64_t particle_steps) {
  const RunSetup& s = parts.setup;
  RunSummary& summary = parts.summary;
  restore_signals(parts.loop_start);
  if (s.domain && !parts.results.gathered) gather_whole(s, parts.results);  // no step was left to run (a resumed run at its end)
  summary.steps = s.state.step - parts.schedule.first_step;
  summary.events = parts.watches.events.fired();
  summary.wall_seconds = std::chrono::duration<double>(Clock::now() - parts.loop_start.start).count();
  summary.particle_steps_per_second = summary.wall_seconds > 0 ? particle_steps / summary.wall_seconds : 0.0;
}

/// The log's account of the run: steps and speed, the end state, each inlet's and outlet's totals.
void tell_end(const RunParts& parts) {
  const RunSetup& s = parts.setup;
  const Model& model = s.model;
  const RunSummary& summary = parts.summary;
  const State& final_state = *parts.results.state;
  const Scalars& final_row = summary.scalars.back();
  fmt::print(s.log, "  done: {} steps to t = {:.6g} s in {:.2f} s ({:.3g} particle-steps/s, {} neighbour-list rebuilds)\n",
             summary.steps, s.state.time, summary.wall_seconds, summary.particle_steps_per_second, s.work.rebuilds);
  fmt::print(s.log, "  end: {} particles, {} contacts, kinetic energy {:.4g} J, max overlap {:.2g} % of radius{}\n",
             final_row.particles, final_row.contacts, final_row.kinetic_translation + final_row.kinetic_rotation,
             100 * final_row.max_overlap_ratio, final_state.lost ? fmt::format(", {} particles left the domain", final_state.lost) : "");
  for (size_t k = 0; k < model.inlets.size(); ++k)
    fmt::print(s.log, "  inlet {}: {} particles, {:.4g} kg{}\n", model.inlets[k].spec.name, final_state.inlets[k].inserted,
               final_state.inlets[k].inserted_mass,
               final_state.inlets[k].failed ? fmt::format(" ({} insertions found the region full)", final_state.inlets[k].failed) : "");
  for (size_t k = 0; k < model.outlets.size(); ++k)
    fmt::print(s.log, "  outlet {}: {} particles, {:.4g} kg\n", model.outlets[k].name, final_state.outlets[k].removed,
               final_state.outlets[k].removed_mass);
}

/// The files of the run's end: the mesh records, the tables and the run record with the end state.
void write_results(const RunParts& parts) {
  const RunSetup& s = parts.setup;
  const Model& model = s.model;
  const State& state = s.state;
  const State& final_state = *parts.results.state;
  if (!model.meshes.empty()) write_mesh_records(model, final_state, s.out);
  // The binned box sensors' profiles over the records window (the same on every rank).
  const bool profiles = profile_bin_total(model) > 0;
  if (profiles) write_file_atomically(s.out + "/stream_profiles.csv", stream_profiles_csv(stream_profile_rows(model, state.stream_profiles)));
  write_tables(parts);
  // The end state's hash: a resumed run and an uninterrupted one compare equal when bitwise equal.
  write_file_atomically(s.out + "/run_info.yaml",
                        run_info(model, s.options, s.run_id) + fmt::format("end:\n  completed: {}\n  time_s: {:.17g}\n  step: {}\n  particles: {}\n"
                                                      "  state_hash: {:016x}\n",
                                                      state.step >= parts.schedule.last_step ? "true" : "false", state.time, state.step,
                                                      final_state.size(), state_hash(final_state, model.history_width)));
  fmt::print(s.log, "  wrote {0}/scalars.csv, {0}/particles.xdmf ({1} frames), {0}/run_info.yaml{2}{3}\n", s.out,
             parts.outputs.frames ? parts.outputs.frames->frames().size() : 0, model.meshes.empty() ? "" : fmt::format(", {}/walls.xdmf", s.out),
             profiles ? fmt::format(", {}/stream_profiles.csv", s.out) : "");
}

/// Under domain decomposition: what it cost rank 0, and how the frames were written.
void tell_domain(const RunParts& parts) {
  const RunSetup& s = parts.setup;
  const Outputs& o = parts.outputs;
  fmt::print(s.log, "  domain (rank 0): {}\n", s.domain->statistics());
  if (o.frames)
    fmt::print(s.log, "  frames: {} {}, {:.3g} s on rank 0\n", o.frames->frames().size(),
               s.collective ? fmt::format("written together by {} ranks (parallel HDF5)", s.domain->ranks()) : "gathered on rank 0", o.frame_seconds);
}

}  // namespace

RunSummary run(const Model& model, State& state, Workspace& work, const RunOptions& options, std::ostream& log) {
  RunSummary summary;
  RunSetup setup = plan_run(model, state, work, options, log, summary);
  if (options.write_files) claim_folder(setup, summary);
  // The run's id, in run_info.yaml and every checkpoint: a new one, or the resumed run's.
  setup.run_id = options.resume ? 0 : new_run_id();
  if (options.resume) {
    resume_from_checkpoint(setup, summary);
    if (summary.already_complete) return summary;
  }
  if (setup.writer) print_setup(model, state, log);
  Watches watches = watch_run(setup);
  if (setup.domain) setup.domain->distribute(state);
  prepare(setup.stepped, state, work);

  WholeResults results{std::nullopt, &state, &work, false};
  RowTotals totals{state.lost, setup.domain ? setup.domain->sum(static_cast<double>(state.owned())) : 0.0};
  if (!setup.collective) gather_whole(setup, results);
  if (!options.resume) add_row(setup, summary, totals);
  const Schedule schedule = schedule_steps(setup);

  Outputs outputs;
  if (options.write_files) begin_writing(setup, summary);
  if (options.write_files && (setup.writer || setup.collective)) open_outputs(setup, results, outputs);
  if (!options.resume && (setup.writer || setup.collective)) check_start(setup, results);

  const LoopStart loop_start = start_loop(setup, watches);
  RunParts parts{setup, summary, watches, results, totals, schedule, outputs, loop_start};
  end_loop(parts, run_steps(parts));
  if (!setup.writer) return summary;

  tell_end(parts);
  if (options.write_files) write_results(parts);
  if (setup.domain) tell_domain(parts);
  if (setup.domain) {  // the caller (reports, renders) gets the whole state, with this instant's forces
    state = std::move(results.whole->evaluated);
    work = std::move(results.whole->work);
  }
  return summary;
}

}  // namespace dem
