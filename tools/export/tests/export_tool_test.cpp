// hystloop-export end to end: a log with known content is written with lcm::LogFile, the tool
// runs on it, and both files are read back with libhdf5 and libmatio: the values bit for bit,
// units, legends and the configuration; bad arguments are refused naming the option.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <matio.h>

#include <sys/wait.h>
#include <unistd.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "hystloop/command_block_t.hpp"
#include "hystloop/control_t.hpp"
#include "hystloop/mem_params_t.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "hystloop/service_status_t.hpp"
#include "hystloop/trajectory_t.hpp"
#include "log_test_support.hpp"

namespace fs = std::filesystem;
using namespace hystloop;
using namespace hystloop::test;

namespace {

constexpr std::int64_t kT0 = 1'700'000'000'000'000;  // the first tick [us]
constexpr std::int64_t kBlocks = 5, kTicks = 4;      // ticks per block
constexpr double kDt = 1e-4;                         // [s]

// Values with every bit of the mantissa in use, a NaN reference, and flags of several bits.
double y_of(std::int64_t k) { return 1e-6 * std::sin(0.37 * static_cast<double>(k)) + 1.0 / 3.0 * 1e-9; }
double u_of(std::int64_t k) { return 100.0 * std::cos(0.11 * static_cast<double>(k)) + M_PI; }
double y_ref_of(std::int64_t k) { return k < 3 ? std::nan("") : 1e-6 * std::sin(0.3 * static_cast<double>(k)); }
std::int32_t flags_of(std::int64_t k) {
  return k < 2 ? std::int32_t{sensor_block_t::SAFE_STATE} | std::int32_t{sensor_block_t::SIMULATED}
               : (k % 5 == 0 ? std::int32_t{sensor_block_t::SATURATED} : 0);
}
// Block b arrives as its last tick is sampled.
std::int64_t block_recv(std::int64_t b) { return kT0 + ((b + 1) * kTicks - 1) * 100; }

std::uint64_t bits(double v) { return std::bit_cast<std::uint64_t>(v); }

void write_log(const fs::path& file) {
  lcm::LogFile log(file.string(), "w");
  ASSERT_TRUE(log.good());
  trajectory_t points{};
  points.utime = kT0;
  points.version = 1;
  points.shape = trajectory_t::POINTS;
  points.n_points = 3;
  points.points_t_s = {0.0, 0.25, 1.0 / 3.0};
  points.points_y_m = {0.0, 1e-6, -0.7e-6};
  write(log, kT0 - 50, "HX_TRAJECTORY", points);
  for (std::int64_t b = 0; b < kBlocks; ++b) {
    sensor_block_t s{};
    s.utime = kT0 + b * kTicks * 100;
    s.seq = b * kTicks;
    s.dt_s = kDt;
    s.buffer_depth_ticks = static_cast<std::int32_t>(20 + b);
    s.n_ticks = kTicks;
    s.n_axes = 1;
    s.n_values = kTicks;
    for (std::int64_t i = 0; i < kTicks; ++i) {
      const std::int64_t k = b * kTicks + i;
      s.u_V.push_back(u_of(k));
      s.u_ff_V.push_back(u_of(k) - 0.5);
      s.u_fb_V.push_back(0.5);
      s.y_ref_m.push_back(y_ref_of(k));
      s.y_m.push_back(y_of(k));
      s.flags.push_back(flags_of(k));
    }
    write(log, block_recv(b), "HX_SENSOR", s);
    command_block_t c{};
    c.utime = block_recv(b);
    c.seq = (b + 1) * kTicks;
    c.sample_seq = (b + 1) * kTicks - 1;
    c.n_ticks = kTicks;
    c.n_axes = 1;
    c.n_values = kTicks;
    for (std::int64_t i = 0; i < kTicks; ++i) {
      c.u_ff_V.push_back(u_of(c.seq + i));
      c.y_ref_m.push_back(y_ref_of(c.seq + i));
      c.params_version.push_back(b < 2 ? 0 : 3);
      c.mode.push_back(b < 2 ? command_block_t::MODE_LINEAR : command_block_t::MODE_MEM);
    }
    write(log, block_recv(b) + 30, "HX_COMMAND", c);
  }
  service_status_t st{};
  st.utime = kT0;
  st.process = "bridge";
  st.host = "stage-pc";
  st.pid = 41;
  st.state = service_status_t::DEGRADED;
  st.detail = "late commands";
  st.start_utime = kT0 - 1'000'000;
  st.n_counters = 2;
  st.counter_names = {"ticks", "rejected_nonfinite"};
  st.counter_values = {20, 3};
  st.loop_p50_us = st.loop_p99_us = st.loop_max_us = std::nan("");
  st.latency_p50_us = st.latency_p99_us = st.latency_max_us = std::nan("");
  write(log, kT0 + 1000, "HX_STATUS", st);
  mem_params_t p{};
  p.utime = kT0;
  p.version = 3;
  p.publisher_id = 99;
  p.c1 = 6.3e-9;
  p.c2 = 1.7e-11;
  p.c3 = 0.61;
  p.residual_m = 2e-9;
  p.valid = 1;
  p.source = "reident@h";
  write(log, kT0 + 1100, "HX_PARAMS", p);
  control_t k{};
  k.utime = kT0;
  k.request_id = 5;
  k.command = control_t::SET_MODE;
  k.mode = command_block_t::MODE_MEM;
  write(log, kT0 + 1200, "HX_CONTROL", k);
  write(log, kT0 + 1300, "OTHER_RIG_SENSOR", k);  // another rig's channel: not exported by default
}

ToolRun run_tool(const std::string& args, const fs::path& scratch) {
  return test::run_tool(HYSTLOOP_EXPORT_EXE, args, scratch);
}

// Reading HDF5 back through the C API, nothing of the exporter's own code.
class H5 {
 public:
  explicit H5(const fs::path& file) : file_(H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT)) {}
  ~H5() {
    if (file_ >= 0) H5Fclose(file_);
  }
  H5(const H5&) = delete;
  H5& operator=(const H5&) = delete;
  bool ok() const { return file_ >= 0; }
  bool exists(const std::string& path) const { return H5Lexists(file_, path.c_str(), H5P_DEFAULT) > 0; }

  template <class T>
  std::vector<T> values(const std::string& path, hid_t type) const {
    const hid_t set = H5Dopen2(file_, path.c_str(), H5P_DEFAULT);
    if (set < 0) return {};
    const hid_t space = H5Dget_space(set);
    std::vector<T> out(static_cast<std::size_t>(H5Sget_simple_extent_npoints(space)));
    if (!out.empty()) H5Dread(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data());
    H5Sclose(space);
    H5Dclose(set);
    return out;
  }
  std::vector<double> doubles(const std::string& path) const { return values<double>(path, H5T_NATIVE_DOUBLE); }
  std::vector<std::int64_t> ints(const std::string& path) const { return values<std::int64_t>(path, H5T_NATIVE_INT64); }
  std::vector<std::string> strings(const std::string& path) const {
    const hid_t type = H5Tcopy(H5T_C_S1);
    H5Tset_size(type, H5T_VARIABLE);
    H5Tset_cset(type, H5T_CSET_UTF8);
    std::vector<std::string> out;
    for (char* s : values<char*>(path, type)) {
      out.emplace_back(s);
      H5free_memory(s);
    }
    H5Tclose(type);
    return out;
  }
  // A string attribute of the object at `path` ("" if missing).
  std::string attr(const std::string& path, const std::string& name) const {
    if (H5Aexists_by_name(file_, path.c_str(), name.c_str(), H5P_DEFAULT) <= 0) return "";
    const hid_t a = H5Aopen_by_name(file_, path.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT);
    const hid_t type = H5Tcopy(H5T_C_S1);
    H5Tset_size(type, H5T_VARIABLE);
    H5Tset_cset(type, H5T_CSET_UTF8);
    char* s = nullptr;
    std::string out;
    if (H5Aread(a, type, &s) >= 0 && s != nullptr) out = s;
    H5free_memory(s);
    H5Tclose(type);
    H5Aclose(a);
    return out;
  }
  std::int64_t int_attr(const std::string& path, const std::string& name) const {
    std::int64_t v = -1;
    const hid_t a = H5Aopen_by_name(file_, path.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT);
    if (a >= 0) {
      H5Aread(a, H5T_NATIVE_INT64, &v);
      H5Aclose(a);
    }
    return v;
  }

 private:
  hid_t file_;
};

// Reading .mat back through libmatio.
class Mat {
 public:
  explicit Mat(const fs::path& file) : mat_(Mat_Open(file.c_str(), MAT_ACC_RDONLY)) {}
  ~Mat() {
    for (matvar_t* v : vars_) Mat_VarFree(v);
    if (mat_ != nullptr) Mat_Close(mat_);
  }
  Mat(const Mat&) = delete;
  Mat& operator=(const Mat&) = delete;
  bool ok() const { return mat_ != nullptr; }
  matvar_t* var(const std::string& name) {
    matvar_t* v = Mat_VarRead(mat_, name.c_str());
    if (v != nullptr) vars_.push_back(v);
    return v;
  }
  static matvar_t* field(matvar_t* s, const std::string& name) {
    return s == nullptr ? nullptr : Mat_VarGetStructFieldByName(s, name.c_str(), 0);
  }
  static std::vector<double> doubles(matvar_t* v) {
    if (v == nullptr || v->class_type != MAT_C_DOUBLE || v->data == nullptr) return {};
    const auto* d = static_cast<const double*>(v->data);
    return {d, d + v->nbytes / sizeof(double)};
  }
  static std::vector<std::int64_t> ints(matvar_t* v) {
    if (v == nullptr || v->class_type != MAT_C_INT64 || v->data == nullptr) return {};
    const auto* d = static_cast<const std::int64_t*>(v->data);
    return {d, d + v->nbytes / sizeof(std::int64_t)};
  }
  static std::string text(matvar_t* v) {
    if (v == nullptr || v->class_type != MAT_C_CHAR || v->data == nullptr) return "";
    if (v->data_type == MAT_T_UINT16 || v->data_type == MAT_T_UTF16) {  // a 7.3 file's char is UTF-16
      const auto* units = static_cast<const std::uint16_t*>(v->data);
      std::string out;
      for (std::size_t i = 0; i < v->nbytes / 2; ++i) out += static_cast<char>(units[i]);  // the test's text is ASCII
      return out;
    }
    return {static_cast<const char*>(v->data), v->nbytes};
  }

 private:
  mat_t* mat_;
  std::vector<matvar_t*> vars_;
};

class ExportToolTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("hystloop_export_test_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    write_log(dir_ / "run.lcmlog");
    std::ofstream(dir_ / "compensator.yaml") << "compensator:\n  horizon_s: 0.05\n  mode: mem\n";
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string log() const { return (dir_ / "run.lcmlog").string(); }
  ToolRun run(const std::string& args) { return run_tool(log() + " " + args, dir_); }

  // Every logged sensor value, in tick order.
  static std::vector<double> logged(double (*f)(std::int64_t)) {
    std::vector<double> out;
    for (std::int64_t k = 0; k < kBlocks * kTicks; ++k) out.push_back(f(k));
    return out;
  }
  static void expect_bits_equal(const std::vector<double>& got, const std::vector<double>& want, const char* what) {
    ASSERT_EQ(got.size(), want.size()) << what;
    for (std::size_t i = 0; i < want.size(); ++i) EXPECT_EQ(bits(got[i]), bits(want[i])) << what << "[" << i << "]";
  }

  fs::path dir_;
};

TEST_F(ExportToolTest, Hdf5HoldsEveryValueWithUnitsLegendsAndConfig) {
  const ToolRun r = run("--hdf5 " + (dir_ / "run.h5").string() + " --config " + (dir_ / "compensator.yaml").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  H5 f(dir_ / "run.h5");
  ASSERT_TRUE(f.ok());
  for (const char* g : {"/HX_SENSOR", "/HX_COMMAND", "/HX_TRAJECTORY", "/HX_STATUS", "/HX_PARAMS", "/HX_CONTROL"}) {
    EXPECT_TRUE(f.exists(g)) << g;
  }
  EXPECT_FALSE(f.exists("/OTHER_RIG_SENSOR")) << "another rig's channel";

  expect_bits_equal(f.doubles("/HX_SENSOR/y_m"), logged(y_of), "y_m");
  expect_bits_equal(f.doubles("/HX_SENSOR/u_V"), logged(u_of), "u_V");
  expect_bits_equal(f.doubles("/HX_SENSOR/y_ref_m"), logged(y_ref_of), "y_ref_m");  // NaN payloads too
  const auto seq = f.ints("/HX_SENSOR/seq");
  const auto flags = f.ints("/HX_SENSOR/flags");
  ASSERT_EQ(seq.size(), static_cast<std::size_t>(kBlocks * kTicks));
  ASSERT_EQ(flags.size(), seq.size());
  for (std::size_t k = 0; k < seq.size(); ++k) {
    EXPECT_EQ(seq[k], static_cast<std::int64_t>(k));
    EXPECT_EQ(flags[k], flags_of(static_cast<std::int64_t>(k)));
  }
  // Time zero is the first tick: the first block's receive time back-dated by its 3 later ticks.
  const auto t = f.doubles("/HX_SENSOR/t_s");
  ASSERT_EQ(t.size(), seq.size());
  EXPECT_EQ(t.front(), 0.0);
  EXPECT_NEAR(t.back(), static_cast<double>(kBlocks * kTicks - 1) * kDt, 1e-9);
  EXPECT_EQ(f.int_attr("/", "time_zero_utime_us"), block_recv(0) - 300);

  EXPECT_EQ(f.attr("/HX_SENSOR/y_m", "units"), "m");
  EXPECT_EQ(f.attr("/HX_SENSOR/u_V", "units"), "V");
  EXPECT_EQ(f.attr("/HX_SENSOR/t_s", "units"), "s");
  EXPECT_EQ(f.attr("/HX_SENSOR/utime_us", "units"), "us");
  EXPECT_EQ(f.attr("/HX_PARAMS/c1_m_per_V", "units"), "m/V");
  EXPECT_EQ(f.attr("/HX_TRAJECTORY/frequency_Hz", "units"), "Hz");
  EXPECT_EQ(f.attr("/HX_SENSOR/flags", "legend"),
            "bits: 1=saturated,2=safe_state,4=simulated,8=slew_limited,16=late_command,32=sensor_fault (0=none)");
  EXPECT_EQ(f.attr("/HX_COMMAND/mode", "legend"), "0=off,1=linear,2=mem,3=pi,4=katalenic,5=experiment");
  EXPECT_EQ(f.attr("/HX_STATUS/state", "legend"), "0=starting,1=healthy,2=degraded,3=safe,4=stopping");
  EXPECT_EQ(f.attr("/HX_TRAJECTORY/shape", "legend"), "0=hold,1=sine,2=cosine,3=triangle,4=points");
  EXPECT_EQ(f.attr("/HX_CONTROL/command", "legend").rfind("1=set_mode,2=set_gains,3=arm,4=disarm,", 0), 0u);
  EXPECT_EQ(f.attr("/HX_SENSOR/y_m", "legend"), "") << "not coded";
  EXPECT_EQ(f.attr("/HX_SENSOR", "lcm_type"), "hystloop.sensor_block_t");
  EXPECT_EQ(f.int_attr("/HX_SENSOR", "rows"), kBlocks * kTicks);
  EXPECT_EQ(f.int_attr("/HX_SENSOR", "events"), kBlocks);

  const auto modes = f.ints("/HX_COMMAND/mode");
  ASSERT_EQ(modes.size(), static_cast<std::size_t>(kBlocks * kTicks));
  EXPECT_EQ(modes.front(), command_block_t::MODE_LINEAR);
  EXPECT_EQ(modes.back(), command_block_t::MODE_MEM);
  // Ragged columns: the points of every row one after the other, counted by n_points.
  expect_bits_equal(f.doubles("/HX_TRAJECTORY/points_t_s"), {0.0, 0.25, 1.0 / 3.0}, "points_t_s");
  EXPECT_EQ(f.ints("/HX_TRAJECTORY/n_points"), std::vector<std::int64_t>{3});
  EXPECT_EQ(f.attr("/HX_TRAJECTORY/points_t_s", "count_column"), "n_points");
  EXPECT_EQ(f.strings("/HX_STATUS/counter_names"), (std::vector<std::string>{"ticks", "rejected_nonfinite"}));
  EXPECT_EQ(f.ints("/HX_STATUS/counter_values"), (std::vector<std::int64_t>{20, 3}));
  EXPECT_EQ(f.strings("/HX_STATUS/process"), std::vector<std::string>{"bridge"});
  EXPECT_EQ(f.strings("/HX_PARAMS/source"), std::vector<std::string>{"reident@h"});
  expect_bits_equal(f.doubles("/HX_PARAMS/c3"), {0.61}, "c3");

  EXPECT_EQ(f.strings("/config/compensator_yaml"), std::vector<std::string>{slurp(dir_ / "compensator.yaml")});
  EXPECT_EQ(f.attr("/config/compensator_yaml", "path"), (dir_ / "compensator.yaml").string());
  EXPECT_EQ(f.attr("/", "rig_prefix"), "HX_");
  EXPECT_NE(f.attr("/", "processes").find("bridge@stage-pc pid 41"), std::string::npos) << f.attr("/", "processes");
  EXPECT_NE(f.attr("/", "channels").find("OTHER_RIG_SENSOR: 1 events"), std::string::npos);
  EXPECT_NE(r.out.find("HX_SENSOR"), std::string::npos) << r.out;
}

void expect_mat_content(const fs::path& file, const fs::path& config) {
  Mat m(file);
  ASSERT_TRUE(m.ok());
  matvar_t* sensor = m.var("HX_SENSOR");
  ASSERT_NE(sensor, nullptr);
  std::vector<double> y = Mat::doubles(Mat::field(sensor, "y_m"));
  std::vector<double> want;
  for (std::int64_t k = 0; k < kBlocks * kTicks; ++k) want.push_back(y_of(k));
  ASSERT_EQ(y.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i) EXPECT_EQ(bits(y[i]), bits(want[i])) << i;
  matvar_t* y_m = Mat::field(sensor, "y_m");
  ASSERT_NE(y_m, nullptr);
  EXPECT_EQ(y_m->dims[0], want.size()) << "a column vector";
  EXPECT_EQ(y_m->dims[1], 1u);
  const auto seq = Mat::ints(Mat::field(sensor, "seq"));
  ASSERT_EQ(seq.size(), want.size());
  EXPECT_EQ(seq.back(), kBlocks * kTicks - 1);

  matvar_t* meta = m.var("HX_SENSOR_meta");
  ASSERT_NE(meta, nullptr);
  EXPECT_EQ(Mat::text(Mat::field(Mat::field(meta, "units"), "y_m")), "m");
  EXPECT_EQ(Mat::text(Mat::field(Mat::field(meta, "units"), "u_V")), "V");
  EXPECT_EQ(Mat::text(Mat::field(Mat::field(meta, "legend"), "flags")).rfind("bits: 1=saturated,2=safe_state", 0), 0u);
  EXPECT_EQ(Mat::field(Mat::field(meta, "legend"), "y_m"), nullptr) << "only coded columns have a legend";
  EXPECT_EQ(Mat::text(Mat::field(meta, "lcm_type")), "hystloop.sensor_block_t");
  matvar_t* command_meta = m.var("HX_COMMAND_meta");
  EXPECT_EQ(Mat::text(Mat::field(Mat::field(command_meta, "legend"), "mode")),
            "0=off,1=linear,2=mem,3=pi,4=katalenic,5=experiment");

  matvar_t* status = m.var("HX_STATUS");
  matvar_t* names = Mat::field(status, "counter_names");
  ASSERT_NE(names, nullptr);
  ASSERT_EQ(names->class_type, MAT_C_CELL);
  EXPECT_EQ(Mat::text(Mat_VarGetCell(names, 1)), "rejected_nonfinite");

  matvar_t* run = m.var("hystloop_run");
  ASSERT_NE(run, nullptr);
  EXPECT_EQ(Mat::text(Mat::field(Mat::field(run, "config"), "compensator_yaml")), slurp(config));
  EXPECT_EQ(Mat::text(Mat::field(run, "rig_prefix")), "HX_");
  EXPECT_EQ(Mat::ints(Mat::field(run, "time_zero_utime_us")), std::vector<std::int64_t>{block_recv(0) - 300});
}

TEST_F(ExportToolTest, MatHoldsEveryValueWithUnitsLegendsAndConfig) {
  const ToolRun r = run("--mat " + (dir_ / "run.mat").string() + " --config " + (dir_ / "compensator.yaml").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  expect_mat_content(dir_ / "run.mat", dir_ / "compensator.yaml");
}

TEST_F(ExportToolTest, Mat73HoldsTheSame) {
  const ToolRun r = run("--mat " + (dir_ / "run.mat").string() + " --mat-version 7.3 --config " +
                        (dir_ / "compensator.yaml").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  expect_mat_content(dir_ / "run.mat", dir_ / "compensator.yaml");
}

TEST_F(ExportToolTest, ChannelAndTimeRangeSelectRows) {
  // Ticks 4..11 lie in [0.4 ms, 1.1 ms]; the channel named by its suffix.
  const ToolRun r = run("--hdf5 " + (dir_ / "run.h5").string() + " --channel SENSOR --from 0.00035 --to 0.00115");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  H5 f(dir_ / "run.h5");
  ASSERT_TRUE(f.ok());
  EXPECT_TRUE(f.exists("/HX_SENSOR"));
  EXPECT_FALSE(f.exists("/HX_COMMAND"));
  const auto seq = f.ints("/HX_SENSOR/seq");
  ASSERT_EQ(seq.size(), 8u);
  EXPECT_EQ(seq.front(), 4);
  EXPECT_EQ(seq.back(), 11);
  expect_bits_equal(f.doubles("/HX_SENSOR/y_m"),
                    {y_of(4), y_of(5), y_of(6), y_of(7), y_of(8), y_of(9), y_of(10), y_of(11)}, "y_m");
}

TEST_F(ExportToolTest, BadArgumentsAreRefusedNamingTheOption) {
  const std::string h5 = " --hdf5 " + (dir_ / "run.h5").string();
  std::ofstream(dir_ / "bad.yaml") << "a: [1, 2\n";
  const struct {
    std::string args, option;
  } cases[] = {
      {"", "--mat/--hdf5"},
      {h5 + " --channel NO_SUCH", "--channel"},
      {h5 + " --from 2 --to 1", "--to"},
      {h5 + " --config " + (dir_ / "bad.yaml").string(), "--config"},
      {h5 + " --config " + (dir_ / "missing.yaml").string(), "--config"},
      {h5 + " --mat-version 6", "--mat-version"},
      {h5 + " --rig hx", "--rig"},
      {h5 + " --no-such-option", "--no-such-option"},
  };
  for (const auto& c : cases) {
    const ToolRun r = run(c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args << ": " << r.err;
    EXPECT_NE(r.err.find(c.option), std::string::npos) << c.args << ": " << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "run.h5")) << c.args;
  }
  const ToolRun missing = run_tool((dir_ / "no.lcmlog").string() + h5, dir_);
  EXPECT_EQ(missing.exit_code, 2) << missing.err;
}

TEST_F(ExportToolTest, RuntimeFailuresExitOneWithTheReason) {
  ToolRun r = run("--hdf5 " + (dir_ / "no_folder" / "run.h5").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("cannot write: no folder"), std::string::npos) << r.err;
  r = run("--mat " + dir_.string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("it is a folder"), std::string::npos) << r.err;
  std::ofstream(dir_ / "junk.lcmlog") << "not an event log at all";
  r = run_tool((dir_ / "junk.lcmlog").string() + " --hdf5 " + (dir_ / "j.h5").string(), dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no channel of the rig HX_ in the log"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "j.h5"));
  r = run("--hdf5 " + (dir_ / "run.h5").string() + " --rig OTHER_RIG_");
  EXPECT_EQ(r.exit_code, 0) << r.err << " (another rig's channels by --rig)";
}

TEST_F(ExportToolTest, HelpNamesTheExitCodesAndOptions) {
  const ToolRun r = run_tool("--help", dir_);
  EXPECT_EQ(r.exit_code, 0);
  for (const char* s : {"--mat", "--hdf5", "--channel", "--from", "--to", "--config", "--rig", "Exit status: 0"}) {
    EXPECT_NE(r.out.find(s), std::string::npos) << s;
  }
}

// The files as a lab opens them in Python, when python3 has h5py and scipy.
TEST_F(ExportToolTest, PythonReadsBothFiles) {
  std::string python;
  for (const char* candidate : {"python3", "/usr/bin/python3"}) {
    const std::string probe = std::string(candidate) + " -c 'import h5py, scipy.io' >/dev/null 2>&1";
    if (std::system(probe.c_str()) == 0) {
      python = candidate;
      break;
    }
  }
  if (python.empty()) GTEST_SKIP() << "no python3 with h5py and scipy (python3-h5py, python3-scipy)";
  const ToolRun r = run("--hdf5 " + (dir_ / "run.h5").string() + " --mat " + (dir_ / "run.mat").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::string cmd =
      python + " " + HYSTLOOP_EXPORT_PYCHECK + " " + (dir_ / "run.h5").string() + " " + (dir_ / "run.mat").string();
  char hex[64];
  for (std::int64_t k = 0; k < kBlocks * kTicks; ++k) {
    std::snprintf(hex, sizeof hex, " %a", y_of(k));
    cmd += hex;
  }
  cmd += " >" + (dir_ / "py.txt").string() + " 2>&1";
  const int status = std::system(cmd.c_str());
  EXPECT_EQ(status, 0) << slurp(dir_ / "py.txt");
  EXPECT_EQ(slurp(dir_ / "py.txt"), "ok\n");
}

}  // namespace
