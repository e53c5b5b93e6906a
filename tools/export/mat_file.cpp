#include "mat_file.hpp"

#include <matio.h>

#include <memory>
#include <type_traits>
#include <stdexcept>
#include <string>
#include <vector>

namespace hystloop::exporter {

namespace {

struct VarFree {
  void operator()(matvar_t* v) const noexcept { Mat_VarFree(v); }
};
using Var = std::unique_ptr<matvar_t, VarFree>;

// The values stay in ExportContent until the file is written, so matio is given pointers to
// them (MAT_F_DONT_COPY_DATA) instead of copies of a possibly large run. matio's API takes
// them as void* but does not write through them.
void* data_of(const void* p) { return const_cast<void*>(p); }

Var checked(matvar_t* v, const std::string& what) {
  if (v == nullptr) throw std::runtime_error("cannot build the MAT variable " + what);
  return Var(v);
}

// A char array of the text.
Var var(const std::string& s) {
  size_t dims[2] = {s.empty() ? 0U : 1U, s.size()};
  return checked(Mat_VarCreate(nullptr, MAT_C_CHAR, MAT_T_UTF8, 2, dims, s.empty() ? nullptr : data_of(s.data()),
                               MAT_F_DONT_COPY_DATA),
                 "text");
}

// A rows-by-1 double or int64 array of the values at `data`, copied unless flags is MAT_F_DONT_COPY_DATA.
template <class T>
Var numbers(const T* data, std::size_t rows, int flags, const std::string& what) {
  constexpr bool f64 = std::is_floating_point_v<T>;
  size_t dims[2] = {rows, 1};
  return checked(Mat_VarCreate(nullptr, f64 ? MAT_C_DOUBLE : MAT_C_INT64, f64 ? MAT_T_DOUBLE : MAT_T_INT64, 2, dims,
                               rows == 0 ? nullptr : data_of(data), flags),
                 what);
}

// A 1x1 double or int64.
template <class T>
Var var(T value) {
  return numbers(&value, 1, 0, "number");
}

Var column(const Column& c) {
  switch (c.type) {
    case ColumnType::kFloat64: return numbers(c.f64.data(), c.size(), MAT_F_DONT_COPY_DATA, c.name);
    case ColumnType::kInt64: return numbers(c.i64.data(), c.size(), MAT_F_DONT_COPY_DATA, c.name);
    default: {
      size_t dims[2] = {c.size(), 1};
      Var cell = checked(Mat_VarCreate(nullptr, MAT_C_CELL, MAT_T_CELL, 2, dims, nullptr, 0), c.name);
      for (std::size_t i = 0; i < c.text.size(); ++i) {
        Mat_VarSetCell(cell.get(), static_cast<int>(i), var(c.text[i]).release());  // owned by the cell now
      }
      return cell;
    }
  }
}

// A 1x1 struct with these fields, each set from fields[i].second (taken over).
Var structure(const char* name, std::vector<std::pair<std::string, Var>>&& fields) {
  std::vector<const char*> names;
  names.reserve(fields.size());
  for (const auto& f : fields) names.push_back(f.first.c_str());
  size_t dims[2] = {1, 1};
  Var s = checked(
      Mat_VarCreateStruct(name, 2, dims, names.empty() ? nullptr : names.data(), static_cast<unsigned>(names.size())),
      name == nullptr ? "struct" : name);
  for (auto& [field, value] : fields) {
    Mat_VarSetStructFieldByName(s.get(), field.c_str(), 0, value.release());  // owned by the struct now
  }
  return s;
}

Var channel_data(const std::string& name, const ChannelTable& t) {
  std::vector<std::pair<std::string, Var>> fields;
  for (const Column& c : t.columns) fields.emplace_back(c.name, column(c));
  return structure(name.c_str(), std::move(fields));
}

Var channel_meta(const std::string& name, const ChannelTable& t) {
  std::vector<std::pair<std::string, Var>> units, descriptions, legends, ragged;
  for (const Column& c : t.columns) {
    units.emplace_back(c.name, var(c.unit));
    descriptions.emplace_back(c.name, var(c.description));
    if (!c.legend.empty()) legends.emplace_back(c.name, var(c.legend));
    if (!c.count_column.empty()) ragged.emplace_back(c.name, var(c.count_column));
    if (c.per_row > 0) ragged.emplace_back(c.name, var(std::to_string(c.per_row) + " per row"));
  }
  std::vector<std::pair<std::string, Var>> fields;
  fields.emplace_back("channel", var(t.channel));
  fields.emplace_back("lcm_type", var(t.type_name));
  fields.emplace_back("rows", var(static_cast<double>(t.rows)));
  fields.emplace_back("events", var(static_cast<double>(t.events)));
  fields.emplace_back("skipped_events", var(static_cast<double>(t.skipped)));
  fields.emplace_back("units", structure(nullptr, std::move(units)));
  fields.emplace_back("description", structure(nullptr, std::move(descriptions)));
  fields.emplace_back("legend", structure(nullptr, std::move(legends)));
  fields.emplace_back("ragged", structure(nullptr, std::move(ragged)));
  return structure((name + "_meta").c_str(), std::move(fields));
}

Var run_info(const ExportContent& content) {
  std::vector<std::pair<std::string, Var>> fields;
  for (const RunAttribute& a : content.run) {
    if (a.name == "config_files") continue;  // the cell of paths below
    fields.emplace_back(a.name, std::visit([](const auto& value) { return var(value); }, a.value));
  }
  std::vector<std::pair<std::string, Var>> configs;
  size_t dims[2] = {content.configs.size(), 1};
  Var paths = checked(Mat_VarCreate(nullptr, MAT_C_CELL, MAT_T_CELL, 2, dims, nullptr, 0), "config_files");
  for (std::size_t i = 0; i < content.configs.size(); ++i) {
    configs.emplace_back(content.configs[i].name, var(content.configs[i].text));
    Mat_VarSetCell(paths.get(), static_cast<int>(i), var(content.configs[i].path.native()).release());
  }
  fields.emplace_back("config", structure(nullptr, std::move(configs)));
  fields.emplace_back("config_files", std::move(paths));
  return structure("hystloop_run", std::move(fields));
}

}  // namespace

void write_mat(const std::filesystem::path& file, const ExportContent& content, MatVersion version) {
  const auto format = version == MatVersion::kV73 ? MAT_FT_MAT73 : MAT_FT_MAT5;
  mat_t* mat = Mat_CreateVer(file.c_str(), "hystloop-export: a recorded hystloop run (docs/EXPORT.md)", format);
  if (mat == nullptr) throw std::runtime_error(file.string() + ": cannot create the MAT file");
  const std::unique_ptr<mat_t, int (*)(mat_t*)> closer(mat, Mat_Close);
  auto write = [&](Var v) {
    if (Mat_VarWrite(mat, v.get(), MAT_COMPRESSION_ZLIB) != 0) {
      throw std::runtime_error(file.string() + ": cannot write the variable " + v->name +
                               (version == MatVersion::kV5 ? " (over 2 GB? try --mat-version 7.3)" : ""));
    }
  };
  write(run_info(content));
  for (const ChannelTable& t : content.tables) {
    const std::string name = identifier(t.channel, 58);  // room for "_meta" in MATLAB's 63 characters
    write(channel_data(name, t));
    write(channel_meta(name, t));
  }
}

}  // namespace hystloop::exporter
