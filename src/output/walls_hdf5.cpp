// The wall records of every mesh as HDF5 with an XDMF index (results_hdf5.h, write_mesh_fields).
#include <fmt/format.h>
#include <hdf5.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "output/results_hdf5.h"

namespace dem {

void write_mesh_fields(const std::string& directory, const std::vector<MeshFieldSet>& meshes, double time) {
  std::filesystem::create_directories(directory);
  const std::string path = directory + "/walls.h5", temporary = path + ".part";
  const hid_t file = H5Fcreate(temporary.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (file < 0) throw std::runtime_error(fmt::format("cannot write {}", temporary));
  auto dataset = [&](hid_t group, const std::string& name, hid_t type, const void* data, hsize_t rows, hsize_t columns) {
    const hsize_t dims[2] = {rows, columns};
    const hid_t space = H5Screate_simple(columns > 1 ? 2 : 1, dims, nullptr);
    const hid_t set = H5Dcreate2(group, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    const herr_t status = rows ? H5Dwrite(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) : 0;
    H5Dclose(set);
    H5Sclose(space);
    if (set < 0 || status < 0) throw std::runtime_error(fmt::format("cannot write {}:{}", temporary, name));
  };
  std::string grids;
  for (const MeshFieldSet& m : meshes) {
    const hid_t group = H5Gcreate2(file, m.name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    dataset(group, "vertices", H5T_NATIVE_DOUBLE, m.vertices.data(), m.vertices.size(), 3);
    dataset(group, "triangles", H5T_NATIVE_INT32, m.triangles.data(), m.triangles.size(), 3);
    std::string attributes;
    for (const auto& [name, values] : m.fields) {
      dataset(group, name, H5T_NATIVE_DOUBLE, values.data(), values.size(), 1);
      attributes += fmt::format(
          "      <Attribute Name=\"{0}\" AttributeType=\"Scalar\" Center=\"Cell\">\n"
          "        <DataItem Dimensions=\"{1}\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">walls.h5:/{2}/{0}</DataItem>\n"
          "      </Attribute>\n",
          name, values.size(), m.name);
    }
    H5Gclose(group);
    grids += fmt::format(
        "    <Grid Name=\"{0}\" GridType=\"Uniform\">\n"
        "      <Topology TopologyType=\"Triangle\" NumberOfElements=\"{1}\">\n"
        "        <DataItem Dimensions=\"{1} 3\" NumberType=\"Int\" Precision=\"4\" Format=\"HDF\">walls.h5:/{0}/triangles</DataItem>\n"
        "      </Topology>\n"
        "      <Geometry GeometryType=\"XYZ\">\n"
        "        <DataItem Dimensions=\"{2} 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">walls.h5:/{0}/vertices</DataItem>\n"
        "      </Geometry>\n{3}    </Grid>\n",
        m.name, m.triangles.size(), m.vertices.size(), attributes);
  }
  if (H5Fclose(file) < 0) throw std::runtime_error(fmt::format("cannot close {}", temporary));
  std::filesystem::rename(temporary, path);
  const std::string xdmf = fmt::format(
      "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n  <Domain>\n  <Grid Name=\"walls\" GridType=\"Collection\" "
      "CollectionType=\"Spatial\">\n    <Time Value=\"{:.17g}\"/>\n{}  </Grid>\n  </Domain>\n</Xdmf>\n",
      time, grids);
  const std::string xdmf_path = directory + "/walls.xdmf";
  {
    std::ofstream out(xdmf_path + ".part", std::ios::trunc);
    out << xdmf;
    if (!out) throw std::runtime_error(fmt::format("cannot write {}.part", xdmf_path));
  }
  std::filesystem::rename(xdmf_path + ".part", xdmf_path);
}

}  // namespace dem
