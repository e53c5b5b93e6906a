#include "hdf5_file.hpp"

#include <hdf5.h>

#include <algorithm>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace hystloop::exporter {

namespace {

// An HDF5 identifier closed with its own close function when it goes out of scope.
class Handle {
 public:
  Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  ~Handle() {
    if (id_ >= 0) close_(id_);
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  Handle(Handle&& other) noexcept : id_(std::exchange(other.id_, -1)), close_(other.close_) {}
  Handle& operator=(Handle&&) = delete;
  hid_t get() const noexcept { return id_; }
  bool ok() const noexcept { return id_ >= 0; }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

class Writer {
 public:
  explicit Writer(std::filesystem::path file) : file_(std::move(file)) {}

  void check(bool ok, const std::string& what) const {
    if (!ok) throw std::runtime_error(file_.string() + ": cannot write " + what + " (HDF5)");
  }

  Handle vlen_string_type() const {
    Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
    check(type.ok() && H5Tset_size(type.get(), H5T_VARIABLE) >= 0 && H5Tset_cset(type.get(), H5T_CSET_UTF8) >= 0,
          "a string type");
    return type;
  }

  void attribute(hid_t object, const std::string& name, const std::string& text) const {
    const Handle type = vlen_string_type();
    const Handle space(H5Screate(H5S_SCALAR), H5Sclose);
    const Handle attr(H5Acreate2(object, name.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
    const char* data = text.c_str();
    check(attr.ok() && H5Awrite(attr.get(), type.get(), &data) >= 0, "attribute " + name);
  }

  // An int64 or a double.
  template <class T>
  void attribute(hid_t object, const std::string& name, T value) const {
    const hid_t type = std::is_floating_point_v<T> ? H5T_NATIVE_DOUBLE : H5T_NATIVE_INT64;
    const Handle space(H5Screate(H5S_SCALAR), H5Sclose);
    const Handle attr(H5Acreate2(object, name.c_str(), type, space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
    check(attr.ok() && H5Awrite(attr.get(), type, &value) >= 0, "attribute " + name);
  }

  void attribute(hid_t object, const RunAttribute& a) const {
    std::visit([&](const auto& value) { attribute(object, a.name, value); }, a.value);
  }

  // A 1-D dataset of n elements of `type`, chunked and compressed when it holds anything.
  Handle dataset(hid_t group, const std::string& name, hid_t type, std::size_t n, bool compress) const {
    const hsize_t dims[1] = {n};
    const Handle space(H5Screate_simple(1, dims, nullptr), H5Sclose);
    const Handle props(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
    check(space.ok() && props.ok(), "dataset " + name);
    if (compress && n > 0 && H5Zfilter_avail(H5Z_FILTER_DEFLATE) > 0) {
      const hsize_t chunk[1] = {std::min<hsize_t>(n, hsize_t{1} << 16)};
      check(H5Pset_chunk(props.get(), 1, chunk) >= 0 && H5Pset_shuffle(props.get()) >= 0 &&
                H5Pset_deflate(props.get(), 4) >= 0,
            "dataset " + name);
    }
    Handle set(H5Dcreate2(group, name.c_str(), type, space.get(), H5P_DEFAULT, props.get(), H5P_DEFAULT), H5Dclose);
    check(set.ok(), "dataset " + name);
    return set;
  }

  void column(hid_t group, const Column& c) const {
    const std::string where = "dataset " + c.name;
    if (c.type == ColumnType::kText) {
      const Handle type = vlen_string_type();
      const Handle set = dataset(group, c.name, type.get(), c.text.size(), false);
      std::vector<const char*> pointers;
      pointers.reserve(c.text.size());
      for (const auto& s : c.text) pointers.push_back(s.c_str());
      if (!pointers.empty()) {
        check(H5Dwrite(set.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, pointers.data()) >= 0, where);
      }
      describe(set.get(), c);
      return;
    }
    const bool f64 = c.type == ColumnType::kFloat64;
    const hid_t type = f64 ? H5T_NATIVE_DOUBLE : H5T_NATIVE_INT64;
    const Handle set = dataset(group, c.name, f64 ? H5T_IEEE_F64LE : H5T_STD_I64LE, c.size(), true);
    const void* data = f64 ? static_cast<const void*>(c.f64.data()) : static_cast<const void*>(c.i64.data());
    if (c.size() > 0) check(H5Dwrite(set.get(), type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) >= 0, where);
    describe(set.get(), c);
  }

  void describe(hid_t set, const Column& c) const {
    if (c.type != ColumnType::kText) attribute(set, "units", c.unit);
    if (!c.description.empty()) attribute(set, "description", c.description);
    if (!c.legend.empty()) attribute(set, "legend", c.legend);
    if (!c.count_column.empty()) attribute(set, "count_column", c.count_column);
    if (c.per_row > 0) attribute(set, "per_row", static_cast<std::int64_t>(c.per_row));
  }

  void table(hid_t file, const ChannelTable& t) const {
    // A channel name holds no '/' in hystloop, but a log may carry any name.
    std::string name = t.channel;
    std::replace(name.begin(), name.end(), '/', '_');
    if (name.empty() || name == ".") name = std::string(1, '_');  // (a literal trips GCC 12's -Wrestrict)
    const Handle group(H5Gcreate2(file, name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
    check(group.ok(), "group " + name);
    attribute(group.get(), "channel", t.channel);
    attribute(group.get(), "lcm_type", t.type_name);
    attribute(group.get(), "rows", static_cast<std::int64_t>(t.rows));
    attribute(group.get(), "events", static_cast<std::int64_t>(t.events));
    attribute(group.get(), "skipped_events", static_cast<std::int64_t>(t.skipped));
    for (const Column& c : t.columns) column(group.get(), c);
  }

  void configs(hid_t file, const std::vector<ConfigFile>& configs) const {
    const Handle group(H5Gcreate2(file, "config", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
    check(group.ok(), "group config");
    for (const ConfigFile& c : configs) {
      const Handle type = vlen_string_type();
      const Handle space(H5Screate(H5S_SCALAR), H5Sclose);
      const Handle set(
          H5Dcreate2(group.get(), c.name.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
          H5Dclose);
      const char* data = c.text.c_str();
      check(set.ok() && H5Dwrite(set.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, &data) >= 0, "config " + c.name);
      attribute(set.get(), "path", c.path.string());
    }
  }

 private:
  std::filesystem::path file_;
};

}  // namespace

void write_hdf5(const std::filesystem::path& file, const ExportContent& content) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors are reported once, by the exception below
  const Writer w(file);
  const Handle f(H5Fcreate(file.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose);
  if (!f.ok()) throw std::runtime_error(file.string() + ": cannot create the HDF5 file");
  for (const RunAttribute& a : content.run) w.attribute(f.get(), a);
  w.configs(f.get(), content.configs);
  for (const ChannelTable& t : content.tables) w.table(f.get(), t);
  if (H5Fflush(f.get(), H5F_SCOPE_GLOBAL) < 0) throw std::runtime_error(file.string() + ": write failed (HDF5)");
}

}  // namespace hystloop::exporter
