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
    out += fmt::format("  - {{stage: {}, model: {}, source: \"{}\"}}\n", kStageKeys[static_cast<int>(e.spec->stage)],
                       e.spec->name, e.spec->citation);
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
  return FrameWriter(directory, names,
                     {{"software", fmt::format("demdesign {}", DEMDESIGN_VERSION)},
                      {"case", model.source},
                      {"mass_scaling", fmt::format("{:g}", model.mass_scaling)},
                      {"stiffness_scaling", fmt::format("{:g}", model.stiffness_scaling)},
                      {"time_step_s", fmt::format("{:.9g}", model.dt)}});
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
    law += fmt::format("{}{}: {}", law.empty() ? "" : ", ", kStageKeys[static_cast<int>(e.spec->stage)], e.spec->name);
  fmt::print(log, "  contact law: {}\n", law);
  for (const ActiveEffect& e : model.effects) fmt::print(log, "    {}: {}\n", e.spec->name, e.spec->citation);
  fmt::print(log, "{}\n", model.advice.report);
  if (model.mass_scaling != 1.0 || model.stiffness_scaling != 1.0)
    fmt::print(log, "  SCALING: particle density x {:g} (mass scaling), particle Young's modulus x {:g} (reduced "
                    "stiffness); both are written with every result\n",
               model.mass_scaling, model.stiffness_scaling);
  else
    fmt::print(log, "  scaling: none (mass x 1, stiffness x 1)\n");
  if (model.periodic())
    fmt::print(log, "  periodic: {}{}{} (periods {:g} {:g} {:g} m)\n", model.period[0] > 0 ? "x" : "", model.period[1] > 0 ? "y" : "",
               model.period[2] > 0 ? "z" : "", model.period[0], model.period[1], model.period[2]);
  fmt::print(log, "  neighbour skin {:.3g} m, interaction range {:.3g} m\n", model.skin, model.interaction_range);
  for (const std::string& note : model.notes) fmt::print(log, "  note: {}\n", note);
  for (const std::string& warning : particles_behind_walls(model, state)) fmt::print(log, "  WARNING: {}\n", warning);
}

RunSummary run(const Model& model, State& state, Workspace& work, const RunOptions& options, std::ostream& log) {
  RunSummary summary;
  summary.output_directory = options.output_directory.empty() ? model.output.directory : options.output_directory;
  const std::string out = summary.output_directory;
  const double duration = options.duration >= 0 ? options.duration : model.duration;
  if (!(duration >= 0) || duration / model.dt > 1e15)
    throw CaseError(fmt::format("duration {:g} s is not a time this run can reach ({:.3g} steps of {:.3g} s); valid: 0 to 1e6 s", duration,
                                duration / model.dt, model.dt));
  const std::int64_t end_step = static_cast<std::int64_t>(std::ceil(duration / model.dt - 1e-9));
  // Under domain decomposition every rank steps its share with the domain's model; the ranks
  // write each frame together (options.share_frame) or the root gathers the whole state for it,
  // and the root gathers it for images and at the end and writes the rest as one process would.
  Domain* domain = options.domain;
  const bool writer = domain == nullptr || domain->root();
  const bool collective = domain != nullptr && static_cast<bool>(options.share_frame);
  const Model& stepped = domain ? domain->local_model() : model;
  work.domain = domain;
  // A refusal on the root stops every rank (the others would wait for it forever).
  const auto stop_if_refused = [&](const std::string& refused) {
    if (domain ? domain->any(!refused.empty()) : !refused.empty())
      throw CaseError(!refused.empty() ? refused : "rank 0 refused the output folder (its message is on standard error)");
  };
  // The output folder, claimed by the process that writes the results: refused when it holds
  // another run's results (unless resumed or overwritten) or a file of the run's names that no
  // run wrote; locked until the caller lets go of the summary (run_folder.h).
  if (options.write_files) {
    std::string refused;
    if (writer && options.folder) {
      summary.folder = options.folder;
    } else if (writer) {
      try {
        std::vector<std::string> names = run_output_names();
        names.insert(names.end(), options.caller_outputs.begin(), options.caller_outputs.end());
        const FolderUse use = options.resume ? FolderUse::resume : options.overwrite ? FolderUse::overwrite : FolderUse::fresh;
        summary.folder = std::make_shared<RunFolder>(out, use, names, log);
      } catch (const std::exception& e) {
        refused = e.what();
      }
    }
    stop_if_refused(refused);
  }

  // The run's id, in run_info.yaml and every checkpoint: a new one, or the resumed run's.
  std::uint64_t run_id = options.resume ? 0 : new_run_id();
  if (options.resume) {
    // A run that reached its end has nothing to resume: it is said, not rewound to its last checkpoint.
    const RunRecord record = writer ? read_run_record(out) : RunRecord{};
    bool complete = writer && record.completed && record.step >= end_step;
    if (domain) complete = domain->any(complete);
    if (complete) {
      if (writer)
        fmt::print(log, "  {}: the run is complete (t = {:.6g} s, step {}; run_info.yaml): nothing to resume. To run it again from the "
                        "start, use --overwrite instead of --resume\n", out, record.time, record.step);
      summary.already_complete = true;
      return summary;
    }
    std::string from;
    state = load_resumable(out, model, &from, &run_id);
    // The checkpoint must belong to the rows beside it, or the resumed run would splice two runs.
    const std::int64_t rows_every = model.output.scalars_every > 0 ? model.output.scalars_every : std::max<std::int64_t>(1, end_step / 200);
    stop_if_refused(writer ? foreign_checkpoint(model, out, from, run_id, state, rows_every) : "");
    if (writer) summary.scalars = read_scalars(model, out + "/scalars.csv", state.time);
    if (writer) fmt::print(log, "  resumed from {} at t = {:.6g} s (step {})\n", from, state.time, state.step);
  }
  if (writer) print_setup(model, state, log);
  EnergyWatch energy(model, state, model.energy_rise_limit);
  // First arrivals to the step (events.h); one process only: under domain decomposition each rank
  // holds a share of the particles.
  EventWatch events(model);
  if (options.resume && writer) events.restore(read_events(out + "/events.csv", state.time));
  double last_check = state.time;
  if (domain) domain->distribute(state);
  prepare(stepped, state, work);

  // The whole state for results: the state itself, or (domain) the root's gathered copy with its
  // lists rebuilt (and, for the caller at the end, a copy with this instant's contact forces),
  // gathered for frames unless the ranks write them together, for rendered frames and at the end.
  std::optional<WholeState> whole;
  const State* results = &state;  // positions, counters, histories
  const Workspace* results_work = &work;
  bool gathered = false;  // on every rank alike: whether gather_whole has run
  auto gather_whole = [&]() {
    if (!domain) return;
    gathered = true;
    State gathered_state = domain->gather(state);
    if (!writer) return;
    whole = ready_for_results(model, std::move(gathered_state));
    results = &whole->state, results_work = &whole->work;
  };
  // A row of scalars (collective under domain decomposition): each rank measures its own
  // particles and the contacts it lists, the parts are summed over the ranks and the root
  // finishes the row; no rank gathers the state for it (diagnostics.h).
  std::int64_t lost_total = state.lost;  // every rank's, as of the last row
  const auto measure_row = [&] {
    if (!domain) return measure(model, state, work);
    ScalarParts parts = measure_parts(stepped, state, work);
    domain->sum(parts.sums);
    parts.max_overlap_ratio = domain->max(parts.max_overlap_ratio);
    Scalars row = finish_scalars(model, state, parts);
    lost_total = row.lost;
    return row;
  };
  // Particles in the whole run, for the progress line: every rank's, as of the last row.
  double particles_now = domain ? domain->sum(static_cast<double>(state.owned())) : 0.0;
  if (!collective) gather_whole();
  if (!options.resume) {
    Scalars row = measure_row();
    particles_now = static_cast<double>(row.particles);
    if (writer) summary.scalars.push_back(std::move(row));
  }

  const std::int64_t first_step = state.step;
  std::int64_t last_step = end_step;
  if (options.max_steps >= 0) last_step = std::min(last_step, first_step + options.max_steps);
  const std::int64_t total = std::max<std::int64_t>(last_step - first_step, 0);
  const std::int64_t every =
      model.output.scalars_every > 0 ? model.output.scalars_every : std::max<std::int64_t>(1, end_step / 200);
  const std::int64_t frame_every = std::max<std::int64_t>(
      1, static_cast<std::int64_t>(std::llround((model.output.frames_every > 0 ? model.output.frames_every : duration / 20) / model.dt)));
  const std::int64_t checkpoint_every =
      model.output.checkpoint_every > 0 ? std::max<std::int64_t>(1, std::llround(model.output.checkpoint_every / model.dt)) : 0;

  std::optional<FrameWriter> frames;
  double frame_seconds = 0;  // [s] this rank's time writing frames
  const auto write_frame_now = [&](const State& whole_or_mine) {
    const auto begun = std::chrono::steady_clock::now();
    if (collective) {
      const FrameShare share = options.share_frame(state.owned());
      write_frame(*frames, state, &share);
    } else {
      write_frame(*frames, whole_or_mine);
    }
    frame_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - begun).count();
  };
  // Just before the first write: an earlier run's files go (overwrite) and the folder is listed.
  if (options.write_files) {
    std::string failed;
    if (writer) {
      try {
        summary.folder->begin(log);
      } catch (const std::exception& e) {
        failed = e.what();
      }
    }
    stop_if_refused(failed);
  }
  if (options.write_files && (writer || collective)) {
    if (writer) write_file_atomically(out + "/run_info.yaml", run_info(model, options, run_id));
    frames.emplace(make_frame_writer(model, out));
    if (options.resume && writer) frames->adopt_existing();
    else if (!options.resume) write_frame_now(*results);
  }
  // Trouble present from the start (particles created overlapping): told before the first step.
  // With frames written together no rank holds the whole state: each checks its share.
  if (!options.resume && (writer || collective)) {
    std::optional<NumericalError> found;
    try {
      if (collective) check_numerics(stepped, state, work, model.max_overlap_ratio);
      else check_numerics(model, *results, *results_work, model.max_overlap_ratio);
    } catch (const NumericalError& e) {
      found = e;
    }
    if (collective && domain->any(found.has_value()) && !found)
      found = NumericalError(fmt::format("t = {:.6g} s: another rank found numerical trouble (its message is on standard error)", state.time));
    if (found) {
      if (model.stop_on_trouble) throw *found;
      fmt::print(writer ? log : std::cerr, "  WARNING (numerical_trouble: warn, the run goes on): {}\n", found->what());
    }
  }
  // The rows so far, the events and the ParaView script (at checkpoints, on trouble, at the end).
  const auto write_tables = [&] {
    write_file_atomically(out + "/scalars.csv", scalars_csv(model, summary.scalars));
    write_file_atomically(out + "/events.csv", events_csv(events.fired()));
    if (frames) write_paraview_script(out);
  };
  stop_signal = 0;
  auto previous_int = std::signal(SIGINT, on_stop_signal);
  auto previous_term = std::signal(SIGTERM, on_stop_signal);
  // Numerical trouble: checked every few steps (cheap next to a step), so it is caught within
  // a few steps of its start, not at the next row of scalars.
  const std::int64_t check_every = std::min<std::int64_t>(every, 10);
  if (!energy.active() && writer) fmt::print(log, "  energy check: off ({})\n", energy.source());
  std::int64_t lost_reported = state.lost, warnings = 0;
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  auto trouble = [&](const NumericalError& e) {
    if (model.stop_on_trouble) {
      // Keep what was computed: the rows so far and a run record that says why it ended (the last
      // checkpoint stays as it was).
      summary.stopped = fmt::format("numerical trouble: {}", e.what());
      summary.steps = state.step - first_step;
      summary.events = events.fired();
      summary.wall_seconds = std::chrono::duration<double>(Clock::now() - start).count();
      if (options.write_files && writer) {
        try {
          write_tables();
          write_file_atomically(out + "/run_info.yaml", run_info(model, options, run_id) +
                                                            fmt::format("end:\n  completed: false\n  time_s: {:.17g}\n  step: {}\n  stopped: {}\n",
                                                                        state.time, state.step, yaml_quoted(summary.stopped)));
        } catch (const std::exception&) {
        }
      }
      std::signal(SIGINT, previous_int);
      std::signal(SIGTERM, previous_term);
      throw RunStopped(e, summary);
    }
    if (warnings++ < 20) fmt::print(writer ? log : std::cerr, "  WARNING (numerical_trouble: warn, the run goes on): {}\n", e.what());
  };

  auto last_progress = start;
  // What a kill (SIGKILL, the OOM killer, a power cut) may cost: the rows since the last save
  // (output.rows_seconds of wall time) and the computing since the last checkpoint
  // (output.checkpoint_seconds, or checkpoint_every).
  auto last_rows_saved = start, last_checkpoint = start;
  const auto seconds_since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
  std::int64_t particle_steps = 0;
  std::int64_t loop_frames = 0;  // frames written in the loop; on_frame follows every render_every-th
  // Steps until the next one that checks, records or writes run as one advance() (each closing
  // kick gives the next step's drift, step.h); under domain decomposition one at a time.
  const auto steps_to_next_event = [&] {
    std::int64_t steps = last_step - state.step;
    for (const std::int64_t every_n : {check_every, every, frame_every, checkpoint_every})
      if (every_n > 0) steps = std::min(steps, every_n - state.step % every_n);
    return std::max<std::int64_t>(steps, 1);
  };
  while (state.step < last_step) {
    if (domain) {
      step(stepped, state, work);
      particle_steps += static_cast<std::int64_t>(particles_now);
    } else {
      particle_steps += advance(stepped, state, work, steps_to_next_event());
    }
    const bool last = state.step == last_step;
    const bool check_due = state.step % check_every == 0 || last;
    // A signal stops every rank at the same step.
    const bool stopping = domain ? check_due && domain->any(stop_signal != 0) : stop_signal != 0;
    const bool scalars_due = state.step % every == 0 || last;
    const bool frame_due = options.write_files && (state.step % frame_every == 0 || last);
    // A checkpoint on the wall clock: the root's clock decides, for every rank at the same step.
    bool checkpoint_timed = options.write_files && model.output.checkpoint_seconds > 0 && !last &&
                            (!domain || check_due) && writer && seconds_since(last_checkpoint) >= model.output.checkpoint_seconds;
    if (domain && check_due) checkpoint_timed = domain->any(checkpoint_timed);
    const bool checkpoint_due = options.write_files && ((checkpoint_every && state.step % checkpoint_every == 0) || stopping || checkpoint_timed);
    if (checkpoint_due) last_checkpoint = Clock::now(), last_rows_saved = last_checkpoint;
    const bool render_due = frame_due && options.on_frame &&
                            (last || (model.output.render_every > 0 && loop_frames % model.output.render_every == 0));
    if (frame_due) ++loop_frames;
    // A checkpoint needs no gather: each rank writes its share (checkpoint.h); nor does a frame
    // the ranks write together.
    if (domain && ((frame_due && !collective) || render_due || last || stopping)) gather_whole();
    if (check_due) {
      // Under domain decomposition every rank's energy, summed before any rank may throw; the
      // root judges it.
      const double energy_total = domain && energy.active() ? domain->sum(mechanical_energy(stepped, state)) : 0.0;
      std::optional<NumericalError> found;
      try {
        check_numerics(stepped, state, work, model.max_overlap_ratio);
        if (!domain) energy.check(model, state);
        else if (writer) energy.check(model, state, energy_total);
      } catch (const NumericalError& e) {
        found = e;
      }
      if (domain && domain->any(found.has_value()) && !found)
        found = NumericalError(fmt::format("t = {:.6g} s: another rank found numerical trouble (its message is on standard error)", state.time));
      if (found) trouble(*found);
      if (!domain && events.check(stepped, state, last_check) && writer && options.progress)
        for (auto e = events.fired().rbegin(); e != events.fired().rend() && e->step > state.step - check_every; ++e)
          fmt::print(log, "  t = {:.6g} s (step {}): {} (particle {})\n", e->time, e->step, e->what, e->particle);
      last_check = state.time;
      // Under domain decomposition the count is every rank's as of the last row, and the
      // particle named is the last the root knows of (its own, or of the last gathered state).
      const std::int64_t lost_now = domain ? lost_total : state.lost;
      if (writer && lost_now > lost_reported) {
        const auto& p = state.lost > 0 || !domain ? state.last_lost : results->last_lost;
        const bool named = state.lost > 0 || (domain && results->lost > 0);
        // The first loss, then each tenfold: a leak is told, not repeated every step.
        if (lost_reported == 0 || lost_now >= 10 * lost_reported) {
          fmt::print(log, "  WARNING: t = {:.6g} s: {} particles have left the domain (simulation.domain) and were removed; {}Likely "
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
    if (scalars_due) {
      Scalars row = measure_row();
      particles_now = static_cast<double>(row.particles);
      if (writer) summary.scalars.push_back(std::move(row));
      if (writer && options.write_files && !checkpoint_due && !last && model.output.rows_seconds > 0 &&
          seconds_since(last_rows_saved) >= model.output.rows_seconds) {
        write_tables();
        last_rows_saved = Clock::now();
      }
    }
    if (frames && frame_due) {
      write_frame_now(*results);
      if (render_due && writer) options.on_frame(model, *results, *results_work, out, last);
    }
    if (checkpoint_due && domain) {
      // Every rank's share on disk before the root names the step: a failed write on any rank
      // stops every rank, the last complete checkpoint kept.
      std::string failed;
      try {
        save_checkpoint_share(out, model, state.step, domain->rank(), domain->ranks(), pack_share(state, stepped.history_width));
      } catch (const std::exception& e) {
        failed = e.what();
      }
      if (domain->any(!failed.empty()))
        throw std::runtime_error(failed.empty() ? fmt::format("t = {:.6g} s: another rank could not write its checkpoint share (its log says why)", state.time)
                                                : failed);
      if (writer) {
        commit_checkpoint_shares(out, model, state, run_id);
        write_tables();
      }
    } else if (checkpoint_due && writer) {
      save_whole_checkpoint(out, model, *results, run_id);
      write_tables();
    }
    if (stopping) {
      summary.stopped = fmt::format("stopped by signal {} at t = {:.6g} s; checkpoint written, resume with --resume", int(stop_signal), state.time);
      if (writer)
        fmt::print(log, "  stopped by signal {} at t = {:.6g} s; checkpoint written, resume with --resume\n", int(stop_signal),
                   state.time);
      break;
    }
    const auto now = Clock::now();
    if (writer && options.progress && std::chrono::duration<double>(now - last_progress).count() >= model.output.progress_seconds) {
      last_progress = now;
      const double elapsed = std::chrono::duration<double>(now - start).count();
      const std::int64_t done = state.step - first_step;
      const double left = elapsed / static_cast<double>(done) * static_cast<double>(last_step - state.step);
      fmt::print(log, "  t = {:.4g} / {:.4g} s ({:.0f} %), {} particles, {:.3g} particle-steps/s, time left {}\n",
                 state.time, duration, 100.0 * done / std::max<std::int64_t>(total, 1), domain ? static_cast<std::size_t>(particles_now) : state.size(),
                 particle_steps / elapsed,
                 format_duration(left));
      log.flush();
    }
  }
  std::signal(SIGINT, previous_int);
  std::signal(SIGTERM, previous_term);
  if (domain && !gathered) gather_whole();  // no step was left to run (a resumed run at its end)
  summary.steps = state.step - first_step;
  summary.events = events.fired();
  summary.wall_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  summary.particle_steps_per_second = summary.wall_seconds > 0 ? particle_steps / summary.wall_seconds : 0.0;
  if (!writer) return summary;

  const State& final_state = *results;
  const Scalars& final_row = summary.scalars.back();
  fmt::print(log, "  done: {} steps to t = {:.6g} s in {:.2f} s ({:.3g} particle-steps/s, {} neighbour-list rebuilds)\n",
             summary.steps, state.time, summary.wall_seconds, summary.particle_steps_per_second, work.rebuilds);
  fmt::print(log, "  end: {} particles, {} contacts, kinetic energy {:.4g} J, max overlap {:.2g} % of radius{}\n",
             final_row.particles, final_row.contacts, final_row.kinetic_translation + final_row.kinetic_rotation,
             100 * final_row.max_overlap_ratio, final_state.lost ? fmt::format(", {} particles left the domain", final_state.lost) : "");
  for (size_t k = 0; k < model.inlets.size(); ++k)
    fmt::print(log, "  inlet {}: {} particles, {:.4g} kg{}\n", model.inlets[k].spec.name, final_state.inlets[k].inserted,
               final_state.inlets[k].inserted_mass,
               final_state.inlets[k].failed ? fmt::format(" ({} insertions found the region full)", final_state.inlets[k].failed) : "");
  for (size_t k = 0; k < model.outlets.size(); ++k)
    fmt::print(log, "  outlet {}: {} particles, {:.4g} kg\n", model.outlets[k].name, final_state.outlets[k].removed,
               final_state.outlets[k].removed_mass);
  if (options.write_files && !model.meshes.empty()) write_mesh_records(model, final_state, out);
  if (options.write_files) {
    write_tables();
    // The end state's hash: a resumed run and an uninterrupted one compare equal when bitwise equal.
    write_file_atomically(out + "/run_info.yaml",
                          run_info(model, options, run_id) + fmt::format("end:\n  completed: {}\n  time_s: {:.17g}\n  step: {}\n  particles: {}\n"
                                                        "  state_hash: {:016x}\n",
                                                        state.step >= last_step ? "true" : "false", state.time, state.step,
                                                        final_state.size(), state_hash(final_state, model.history_width)));
    fmt::print(log, "  wrote {0}/scalars.csv, {0}/particles.xdmf ({1} frames), {0}/run_info.yaml{2}\n", out,
               frames ? frames->frames().size() : 0, model.meshes.empty() ? "" : fmt::format(", {}/walls.xdmf", out));
  }
  if (domain) fmt::print(log, "  domain (rank 0): {}\n", domain->statistics());
  if (domain && frames)
    fmt::print(log, "  frames: {} {}, {:.3g} s on rank 0\n", frames->frames().size(),
               collective ? fmt::format("written together by {} ranks (parallel HDF5)", domain->ranks()) : "gathered on rank 0", frame_seconds);
  if (domain) {  // the caller (reports, renders) gets the whole state, with this instant's forces
    state = std::move(whole->evaluated);
    work = std::move(whole->work);
  }
  return summary;
}

}  // namespace dem
