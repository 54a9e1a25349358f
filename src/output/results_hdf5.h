// Results writer: particle frames as HDF5 files with an XDMF index beside them that ParaView opens
// (File > Open particles.xdmf, "Xdmf3 Reader"). Depends only on the HDF5 C API, fmt and the standard
// library, and not on the engine's State, so it can be tested and reused on its own.
#pragma once

#include <cstddef>
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace dem {

/// One particle frame, as columns (n particles). Pointers stay valid during write_frame.
struct ParticleFrame {
  double time = 0;  // [s]
  std::int64_t step = 0;
  std::size_t count = 0;
  const std::int64_t* id = nullptr;
  const double *x = nullptr, *y = nullptr, *z = nullptr;     // [m] sphere centres
  const double *vx = nullptr, *vy = nullptr, *vz = nullptr;  // [m/s]
  const double *wx = nullptr, *wy = nullptr, *wz = nullptr;  // [rad/s]
  const double* radius = nullptr;                            // [m]
  const std::int32_t* material = nullptr;
  /// Clump (rigid body) index, -1 for a free sphere; may be nullptr -> all -1.
  const std::int32_t* clump = nullptr;
  /// Orientation quaternion of the body the sphere belongs to; all four nullptr -> identity.
  const double *qw = nullptr, *qx = nullptr, *qy = nullptr, *qz = nullptr;
};

/// How the ranks of a split run write one frame together into one file, each rank its own particles
/// as one block of rows (app/mpi/mpi_frames.h makes it, with parallel HDF5's MPI-IO driver). The file
/// holds what one process writes, the rows in rank order; no rank gathers the particles.
struct FrameShare {
  std::size_t offset = 0;   ///< this rank's first row
  std::size_t total = 0;    ///< the rows of every rank
  bool root = true;         ///< this rank publishes the file and keeps the XDMF
  std::int64_t file_access = -1;  ///< HDF5 file-access property list (hid_t) opening the file on every rank
  std::int64_t transfer = -1;     ///< HDF5 dataset-transfer property list (hid_t): collective writes
  /// True on every rank when `ok` is true on every rank (collective): a failed write anywhere
  /// fails the frame on every rank.
  std::function<bool(bool ok)> all;
};

/// One frame listed in the XDMF; `file` is relative to the writer's directory.
struct FrameInfo {
  double time;  // [s]
  std::int64_t step;
  std::string file;
  std::size_t count;
};

/// A particle frame read back from a frame file (owning its columns).
struct StoredFrame {
  double time = 0;  // [s]
  std::int64_t step = 0;
  std::vector<std::int64_t> id;
  std::vector<double> position, velocity;  // (n x 3) [m], [m/s]
  std::vector<double> radius;              // [m]
  std::vector<std::int32_t> material;
  std::size_t size() const { return radius.size(); }
};

/// One triangulated wall with fields per triangle, for ParaView.
struct MeshFieldSet {
  std::string name;
  std::vector<std::array<double, 3>> vertices;         // [m] where the mesh is now
  std::vector<std::array<std::int32_t, 3>> triangles;
  std::vector<std::pair<std::string, std::vector<double>>> fields;  ///< per triangle, name with unit
};

/// Writes DIR/walls.h5 (one group per mesh: vertices, triangles, a dataset per field) and
/// DIR/walls.xdmf (a spatial collection of triangle grids with cell attributes), both atomically.
void write_mesh_fields(const std::string& directory, const std::vector<MeshFieldSet>& meshes, double time);

/// Writes DIR/open_in_paraview.py (atomically): a ParaView Python script that opens DIR's
/// particles.xdmf (spheres scaled by radius, coloured by speed) and walls.xdmf when there is one
/// (coloured by shear work rate), at the last saved time. In ParaView: View > Python Shell > Run
/// Script; or `pvpython` / `pvbatch open_in_paraview.py --png FILE` to render an image.
void write_paraview_script(const std::string& directory);

/// Reads a frame file written by FrameWriter; throws std::runtime_error naming the path.
StoredFrame read_frame(const std::string& path);

/// Writes DIR/frames/frame_NNNNNN.h5 (NNNNNN = step) and keeps DIR/particles.xdmf listing them as a
/// temporal collection.
///
/// Each frame file holds, at its root: datasets `id` (int64, n), `position`, `velocity`,
/// `angular_velocity` (float64, n x 3; m, m/s, rad/s), `radius` (float64, n; m), `material`, `clump`
/// (int32, n), `orientation` (float64, n x 4; w x y z), `speed` (float64, n; |v| in m/s) and
/// `connectivity` (int64, n; 0..n-1, the Polyvertex cells the XDMF needs so ParaView draws the points);
/// string attributes `units` = "SI", `material_names` (comma-separated) and the constructor's
/// attributes, plus `time` (float64, s) and `step` (int64).
///
/// Writes are atomic: a frame goes to `.h5.part` and is renamed to `.h5` after H5Fclose succeeded and
/// the data reached the disk; the XDMF is replaced through a temporary file and a rename. A crash
/// therefore leaves at worst an unlisted `.part` file; every listed frame stays readable.
class FrameWriter {
 public:
  /// Frames go to DIR/frames/frame_000042.h5 and DIR/particles.xdmf. Nothing touches the disk before
  /// the first write_frame. `attributes` (key -> value) are written as HDF5 string attributes on every
  /// frame root (scaling factors, software version). Throws std::invalid_argument for a material name
  /// with a comma, or an empty, repeated or reserved (time, step, units, material_names) key.
  FrameWriter(std::string directory, std::vector<std::string> material_names,
              std::vector<std::pair<std::string, std::string>> attributes);

  /// Writes one frame and relists it in the XDMF. A frame whose step is not after the last listed one
  /// (a run resumed from an earlier restart point) first drops the listed frames from that step on.
  /// Throws std::invalid_argument for a missing column, std::runtime_error with the path on an I/O
  /// failure (e.g. disk full); the XDMF then still lists the frames it listed before.
  void write_frame(const ParticleFrame& frame);
  /// The same written by every rank of a split run together (collective): `mine` holds this rank's
  /// particles, `share` where they go. Only the share's root touches the XDMF; every rank throws when
  /// any rank failed.
  void write_frame(const ParticleFrame& mine, const FrameShare& share);

  const std::vector<FrameInfo>& frames() const { return frames_; }

  /// Re-reads DIR/particles.xdmf's frame list (used after a restart, so a resumed run appends to the
  /// same XDMF). No XDMF yet -> empty list. Throws std::runtime_error with the path if it cannot be
  /// read or was not written by this class.
  void adopt_existing();

  const std::string& directory() const { return directory_; }

 private:
  void write_hdf5(const std::string& path, const ParticleFrame& frame, const FrameShare& share);
  void check_columns(const ParticleFrame& frame) const;
  /// Makes the frames directory and unlists the frames from `step` on (a resumed run rewinds).
  void prepare(std::int64_t step);
  /// Publishes the complete `part` file under the frame's name and lists it in the XDMF.
  void publish_and_list(const std::string& part, const FrameInfo& frame);
  void write_xdmf(const std::vector<FrameInfo>& frames) const;

  std::string directory_;
  std::string material_names_;  ///< comma-separated
  std::vector<std::pair<std::string, std::string>> attributes_;
  std::vector<FrameInfo> frames_;
  // Scratch reused between frames: n x 3 interleaved vectors, n x 4 quaternions, n scalars.
  std::vector<double> vec3_, quat_, scalar_;
  std::vector<std::int32_t> int32_;
  std::vector<std::int64_t> int64_;
};

}  // namespace dem
