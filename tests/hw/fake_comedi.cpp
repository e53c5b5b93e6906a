// The fake comedi card (see fake_comedi.hpp). Only the calls the bridge uses; each behaves as
// comedilib documents it for a board like the one described there.
#include "fake_comedi.hpp"

#include <sys/mman.h>
#include <time.h>

#include <cerrno>
#include <cmath>
#include <limits>
#include <new>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

struct comedi_t_struct {
  int unused = 0;
};

namespace fake_comedi {
namespace {

constexpr unsigned kAi = 0, kAo = 1, kDio = 2;
comedi_range kAiRanges[] = {{-10.0, 10.0, UNIT_volt}, {-5.0, 5.0, UNIT_volt}, {-1.0, 1.0, UNIT_volt}};
comedi_range kAoRanges[] = {{-10.0, 10.0, UNIT_volt}, {0.0, 10.0, UNIT_volt}};
comedi_range kDioRange = {0.0, 5.0, UNIT_volt};
comedi_t_struct g_device;
int g_errno = 0;
char g_calibration_path[] = "/var/lib/comedi/calibrations/fake_board_comedi0";
comedi_calibration_t g_calibration{};

void configure_from_environment(State& s) {
  const char* env = std::getenv("HX_FAKE_COMEDI");
  const std::string spec = env != nullptr ? env : "";
  std::size_t pos = 0;
  while (pos < spec.size()) {
    const std::size_t end = spec.find(',', pos) == std::string::npos ? spec.size() : spec.find(',', pos);
    const std::string item = spec.substr(pos, end - pos);
    const std::size_t eq = item.find('=');
    if (eq != std::string::npos) {
      const std::string key = item.substr(0, eq);
      const double value = std::strtod(item.c_str() + eq + 1, nullptr);
      if (key == "mirror_gain") s.mirror_gain = value;
      if (key == "mirror_offset_V") s.mirror_offset_V = value;
      if (key == "calibration") s.calibration = value != 0.0;
      if (key == "open_fails") s.open_fails = value != 0.0;
      if (key == "mirror_by_channel" && value != 0.0) {
        for (unsigned c = 0; c < kAiChannels; ++c) s.mirror_ao[c] = c % kAoChannels;
      }
    }
    pos = end + 1;
  }
}

State make_state() {
  State s;
  s.lists.reserve(1 << 18);
  s.reads.reserve(1 << 12);
  configure_from_environment(s);
  return s;
}

const comedi_range* range_of(unsigned subdevice, unsigned range) {
  if (subdevice == kAi && range < 3) return &kAiRanges[range];
  if (subdevice == kAo && range < 2) return &kAoRanges[range];
  if (subdevice == kDio && range == 0) return &kDioRange;
  return nullptr;
}

double range_to_V(lsampl_t counts, const comedi_range& r) {
  return r.min + (r.max - r.min) * static_cast<double>(counts) / static_cast<double>(kMaxdata);
}

lsampl_t range_from_V(double volts, const comedi_range& r) {
  const double s = (volts - r.min) / (r.max - r.min) * kMaxdata;
  if (!(s >= 0.0)) return 0;
  if (s > kMaxdata) return kMaxdata;
  return static_cast<lsampl_t>(std::floor(s + 0.5));
}

double apply_polynomial(const comedi_polynomial_t& p, double x) {
  double value = 0.0, term = 1.0;
  for (unsigned i = 0; i <= p.order; ++i) {
    value += p.coefficients[i] * term;
    term *= x - p.expansion_origin;
  }
  return value;
}

bool fail(int error) {
  g_errno = error;
  return false;
}

}  // namespace

State& state() {
  static State s = make_state();
  return s;
}

SharedRecord& shared() {
  static SharedRecord* record = [] {
    void* p = ::mmap(nullptr, sizeof(SharedRecord), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) std::abort();
    return new (p) SharedRecord;
  }();
  return *record;
}

std::int64_t monotonic_ns() noexcept {
  timespec t{};
  ::clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<std::int64_t>(t.tv_sec) * 1'000'000'000 + t.tv_nsec;
}

void reset() {
  State& s = state();
  std::vector<InsnList> lists = std::move(s.lists);
  std::vector<ScriptedRead> reads = std::move(s.reads);
  lists.clear();
  reads.clear();
  s = State{};
  s.lists = std::move(lists);
  s.reads = std::move(reads);
  SharedRecord& r = shared();
  r.events = 0;
  r.dio = 0;
  r.last_dio_edge_ns = 0;
}

double softcal_gain() noexcept { return 1.01; }
double softcal_offset_V() noexcept { return 0.002; }

}  // namespace fake_comedi

using namespace fake_comedi;

extern "C" {

comedi_t* comedi_open(const char* fn) {
  State& s = state();
  if (s.open_fails || fn == nullptr || std::strncmp(fn, "/dev/comedi", 11) != 0) {
    g_errno = ENOENT;
    return nullptr;
  }
  ++s.opens;
  return &g_device;
}

int comedi_close(comedi_t* it) {
  if (it != &g_device) return -1;
  State& s = state();
  ++s.closes;
  if (const char* log = std::getenv("HX_FAKE_COMEDI_LOG")) {
    if (std::FILE* f = std::fopen(log, "a")) {
      // Then what each output channel holds (its last code): every axis's safe code after a stop.
      std::fprintf(f, "writes %ld first %u (%.6g V) last %u (%.6g V) holds", s.writes, s.first_write,
                   range_to_V(s.first_write, kAoRanges[0]), s.last_write, range_to_V(s.last_write, kAoRanges[0]));
      for (unsigned c = 0; c < kAoChannels; ++c) std::fprintf(f, " ao%u=%u/%ld", c, s.ao_counts[c], s.ao_writes[c]);
      // The digital lines: their levels (bit c: channel c), which are outputs, and the writes.
      std::fprintf(f, " dio=%u outputs=%u dio_writes=%ld\n", shared().dio.load(), s.dio_output, s.dio_writes);
      std::fclose(f);
    }
  }
  return 0;
}

const char* comedi_strerror(int errnum) { return errnum == ENOENT ? "No such device (fake)" : "fake comedi error"; }
int comedi_errno(void) { return g_errno; }

int comedi_get_n_subdevices(comedi_t*) { return 3; }
const char* comedi_get_driver_name(comedi_t*) { return "fake_driver"; }
const char* comedi_get_board_name(comedi_t*) { return "fake_board"; }

int comedi_get_subdevice_type(comedi_t*, unsigned int subdevice) {
  switch (subdevice) {
    case kAi: return COMEDI_SUBD_AI;
    case kAo: return COMEDI_SUBD_AO;
    case kDio: return COMEDI_SUBD_DIO;
    default: return fail(EINVAL) ? 0 : -1;
  }
}

int comedi_get_subdevice_flags(comedi_t*, unsigned int subdevice) {
  const int soft = state().calibration ? SDF_SOFT_CALIBRATED : 0;
  switch (subdevice) {
    case kAi: return SDF_READABLE | SDF_GROUND | SDF_COMMON | SDF_DIFF | soft;
    case kAo: return SDF_WRITABLE | SDF_GROUND | soft;
    case kDio: return SDF_READABLE | SDF_WRITABLE;
    default: return fail(EINVAL) ? 0 : -1;
  }
}

int comedi_get_n_channels(comedi_t*, unsigned int subdevice) {
  switch (subdevice) {
    case kAi: return 16;
    case kAo: return static_cast<int>(kAoChannels);
    case kDio: return 8;
    default: return fail(EINVAL) ? 0 : -1;
  }
}

lsampl_t comedi_get_maxdata(comedi_t*, unsigned int subdevice, unsigned int) {
  return subdevice == kDio ? 1 : subdevice < 3 ? kMaxdata : 0;
}

int comedi_get_n_ranges(comedi_t*, unsigned int subdevice, unsigned int) {
  return subdevice == kAi ? 3 : subdevice == kAo ? 2 : subdevice == kDio ? 1 : -1;
}

comedi_range* comedi_get_range(comedi_t*, unsigned int subdevice, unsigned int, unsigned int range) {
  return const_cast<comedi_range*>(range_of(subdevice, range));
}

double comedi_to_phys(lsampl_t data, comedi_range* rng, lsampl_t maxdata) {
  if (rng == nullptr || maxdata == 0) return std::numeric_limits<double>::quiet_NaN();
  if (data == 0 || data == maxdata)
    return std::numeric_limits<double>::quiet_NaN();  // COMEDI_OOR_NAN, comedilib's default
  return rng->min + (rng->max - rng->min) * static_cast<double>(data) / static_cast<double>(maxdata);
}

lsampl_t comedi_from_phys(double data, comedi_range* rng, lsampl_t maxdata) {
  if (rng == nullptr || maxdata == 0) return 0;
  const double s = (data - rng->min) / (rng->max - rng->min) * maxdata;
  if (!(s >= 0.0)) return 0;
  if (s > maxdata) return maxdata;
  return static_cast<lsampl_t>(std::floor(s + 0.5));
}

int comedi_do_insnlist(comedi_t* it, comedi_insnlist* il) {
  State& s = state();
  if (it != &g_device || il == nullptr) return fail(EINVAL) ? 0 : -1;
  InsnList record;
  record.n_insns = il->n_insns;
  int done = 0;
  bool read_failed = false;
  bool wrote = false;
  SharedRecord& shared_record = shared();
  for (unsigned i = 0; i < il->n_insns; ++i) {
    comedi_insn& insn = il->insns[i];
    const unsigned chan = CR_CHAN(insn.chanspec);
    if (insn.insn == INSN_WRITE && insn.subdev == kAo && chan < kAoChannels) {
      s.ao_counts[chan] = insn.data[0];
      s.ao_range[chan] = CR_RANGE(insn.chanspec);
      ++s.ao_writes[chan];
      if (s.writes++ == 0) s.first_write = insn.data[0];
      s.last_write = insn.data[0];
      wrote = true;
      ++done;
    } else if (insn.insn == INSN_WRITE && insn.subdev == kDio && chan < kDioChannels) {
      const unsigned before = shared_record.dio.load();
      const unsigned after = insn.data[0] != 0 ? before | (1u << chan) : before & ~(1u << chan);
      if (after != before) shared_record.last_dio_edge_ns = monotonic_ns();
      shared_record.dio = after;
      ++s.dio_writes;
      wrote = true;
      ++done;
    } else if (insn.insn == INSN_READ && insn.subdev == kAi) {
      if (s.next_read < s.reads.size()) {
        const ScriptedRead& r = s.reads[s.next_read++];
        if (r.rc < 0) {
          read_failed = true;
          done = -1;
        } else if (r.rc < 2) {
          read_failed = true;
        } else {
          insn.data[0] = r.counts;
          ++done;
        }
      } else if (chan < kAiChannels) {
        const unsigned ao = s.mirror_ao[chan] % kAoChannels;
        const double ao_V = range_to_V(s.ao_counts[ao], kAoRanges[s.ao_range[ao] % 2]);
        insn.data[0] = range_from_V(s.mirror_gain * s.mirror_scale[chan] * ao_V + s.mirror_offset_V,
                                    kAiRanges[CR_RANGE(insn.chanspec) % 3]);
        ++done;
      } else {
        g_errno = EINVAL;
        read_failed = true;
      }
    } else {
      g_errno = EINVAL;
      read_failed = true;
    }
    if (i < kRecordedInsns) record.insns[i] = {insn.insn, insn.subdev, insn.chanspec, insn.n, insn.data[0]};
    if (read_failed) break;
  }
  if (s.lists.size() < s.lists.capacity()) s.lists.push_back(record);
  if (wrote) {
    const std::uint64_t n = shared_record.events.load();
    OutputEvent& e = shared_record.ring[n % kSharedEvents];
    e.t_ns = monotonic_ns();
    for (unsigned c = 0; c < kAoChannels; ++c) e.ao[c] = s.ao_counts[c];
    e.dio = shared_record.dio.load();
    shared_record.events = n + 1;
  }
  if (read_failed) g_errno = EIO;
  return done;
}

int comedi_dio_config(comedi_t* it, unsigned int subdevice, unsigned int chan, unsigned int direction) {
  State& s = state();
  if (it != &g_device || subdevice != kDio || chan >= kDioChannels) return fail(EINVAL) ? 0 : -1;
  if (direction == COMEDI_OUTPUT) {
    s.dio_output |= 1u << chan;
  } else {
    s.dio_output &= ~(1u << chan);
  }
  return 0;
}

char* comedi_get_default_calibration_path(comedi_t*) { return strdup(g_calibration_path); }

comedi_calibration_t* comedi_parse_calibration_file(const char* path) {
  if (!state().calibration || path == nullptr || std::strcmp(path, g_calibration_path) != 0) return nullptr;
  return &g_calibration;
}

void comedi_cleanup_calibration(comedi_calibration_t*) {}

int comedi_get_softcal_converter(unsigned subdevice, unsigned, unsigned range,
                                 enum comedi_conversion_direction direction, const comedi_calibration_t* calibration,
                                 comedi_polynomial_t* polynomial) {
  const comedi_range* r = range_of(subdevice, range);
  if (calibration != &g_calibration || r == nullptr || subdevice == kDio || polynomial == nullptr) return -1;
  // counts -> V: the range table's line with a 1 % gain error and a 2 mV offset; V -> counts its inverse.
  const double mid_counts = kMaxdata / 2.0;
  const double mid_V = range_to_V(0, *r) + (r->max - r->min) / 2.0;
  const double V_per_count = (r->max - r->min) / kMaxdata * softcal_gain();
  *polynomial = comedi_polynomial_t{};
  polynomial->order = 1;
  if (direction == COMEDI_TO_PHYSICAL) {
    polynomial->expansion_origin = mid_counts;
    polynomial->coefficients[0] = mid_V + softcal_offset_V();
    polynomial->coefficients[1] = V_per_count;
  } else {
    polynomial->expansion_origin = mid_V + softcal_offset_V();
    polynomial->coefficients[0] = mid_counts;
    polynomial->coefficients[1] = 1.0 / V_per_count;
  }
  return 0;
}

double comedi_to_physical(lsampl_t data, const comedi_polynomial_t* p) { return apply_polynomial(*p, data); }

lsampl_t comedi_from_physical(double data, const comedi_polynomial_t* p) {
  const double value = apply_polynomial(*p, data);
  if (!(value >= 0.0)) return 0;
  return static_cast<lsampl_t>(std::nearbyint(value));
}

}  // extern "C"
