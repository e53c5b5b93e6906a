#pragma once
// A fake comedi card at the library boundary: this file's .cpp defines the comedilib calls
// services/bridge/comedi_backend.cpp and probe_hardware.cpp use (same symbols and signatures as
// comedilib.h), on a scripted board, and records every instruction list. Test executables link
// it (hystloop_fake_comedi, a static library: their own definitions come first in ELF symbol
// lookup, so the real libcomedi.so.0 the bridge library also names is never called); the
// hystloop-bridge binary is run against it as libcomedi.so.0 on LD_LIBRARY_PATH
// (hystloop_fake_libcomedi, same source, comedilib's symbol versions), scripted then through
// the environment: HX_FAKE_COMEDI="mirror_gain=-0.5,calibration=1,open_fails=0" and
// HX_FAKE_COMEDI_LOG=<file> (at comedi_close: the first and last DAC codes written and counts).
//
// The board: subdevice 0 an analog input (16 channels, 16 bit, ranges ±10, ±5, ±1 V, ground/
// common/diff), 1 an analog output (4 channels, 16 bit, ranges ±10 V and 0..10 V), 2 a digital
// I/O. Each input "mirrors" an output: ai channel c volts = mirror_gain * mirror_scale[c] *
// (ao channel mirror_ao[c] volts) + mirror_offset_V (by default every input sees output 0, as on
// a one-axis loopback; HX_FAKE_COMEDI="mirror_by_channel=1" makes input c see output c % 4),
// unless scripted reads are queued. The digital lines (the amplifier enable) are written with
// INSN_WRITE on subdevice 2, after comedi_dio_config made them outputs.
//
// What the outputs did is also kept in memory shared with forked children (shared(): a ring of
// every list's output state, with its time), so that a test can see what a process that died of a
// fatal signal or SIGKILL wrote on its way down.

#include <comedilib.h>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace fake_comedi {

struct Insn {
  unsigned insn = 0;
  unsigned subdev = 0;
  unsigned chanspec = 0;
  unsigned n = 0;
  lsampl_t data = 0;  // the first data word: written (INSN_WRITE) or served (INSN_READ)
};

inline constexpr unsigned kAiChannels = 16;
inline constexpr unsigned kAoChannels = 4;
inline constexpr unsigned kDioChannels = 8;
inline constexpr unsigned kRecordedInsns = 8;  // a tick of 3 axes and an enable line is 7

// One comedi_do_insnlist call (at most kRecordedInsns instructions recorded).
struct InsnList {
  unsigned n_insns = 0;
  Insn insns[kRecordedInsns]{};
};

// One read instruction's outcome, served to the read instructions in order (whichever list and
// place in it). rc >= 2: the read is done and returns `counts`; 0 or 1: this read fails (the list
// stops there: comedi_do_insnlist returns the instructions done before it, as rc 1 did for a
// write-and-read list); -1: the whole call fails (returns -1).
struct ScriptedRead {
  int rc = 2;
  lsampl_t counts = 0;  // what the read returns
};

struct State {
  bool open_fails = false;
  bool calibration = false;  // the board has a calibration file with softcal polynomials
  double mirror_gain = 1.0;
  double mirror_offset_V = 0.0;
  unsigned mirror_ao[kAiChannels]{};  // the output each input sees (all output 0 by default)
  double mirror_scale[kAiChannels] = {1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1};  // each input's own factor
  std::vector<InsnList> lists;      // reserved: recording does not allocate up to its capacity
  std::vector<ScriptedRead> reads;  // served first, in order, before mirroring
  std::size_t next_read = 0;
  int opens = 0;
  int closes = 0;
  lsampl_t ao_counts[kAoChannels]{};  // what each output channel holds now
  unsigned ao_range[kAoChannels]{};   // ... in which range
  long ao_writes[kAoChannels]{};      // writes to each output channel since reset
  long writes = 0;                    // output writes since reset, every channel (also past the record's capacity)
  lsampl_t first_write = 0;           // of any channel
  lsampl_t last_write = 0;
  unsigned dio_output = 0;  // the digital lines comedi_dio_config made outputs (bit c: channel c)
  long dio_writes = 0;      // writes to digital lines since reset
};

// The outputs after one instruction list that wrote any: every analog output's code and the
// digital lines' levels (bit c: channel c), at CLOCK_MONOTONIC t_ns.
struct OutputEvent {
  std::int64_t t_ns = 0;
  lsampl_t ao[kAoChannels]{};
  unsigned dio = 0;
};

inline constexpr std::size_t kSharedEvents = std::size_t{1} << 15;

struct SharedRecord {
  std::atomic<std::uint64_t> events{0};           // lists recorded; the ring holds the last kSharedEvents
  std::atomic<unsigned> dio{0};                   // the digital lines' levels now
  std::atomic<std::int64_t> last_dio_edge_ns{0};  // when a digital line last changed (CLOCK_MONOTONIC)
  OutputEvent ring[kSharedEvents];

  // Event i (i < events), when still in the ring.
  const OutputEvent& event(std::uint64_t i) const noexcept { return ring[i % kSharedEvents]; }
};

// Shared anonymous memory, made at the first call (or reset()): call it before fork().
SharedRecord& shared();
std::int64_t monotonic_ns() noexcept;

// The fake's state; reset() brings back the defaults above and empties the record.
State& state();
void reset();

// The range tables' conversions (as comedilib's comedi_to_phys / comedi_from_phys).
inline constexpr lsampl_t kMaxdata = 65535;
// The fake softcal polynomials (when calibration is on): counts -> V for the output and input
// have a 1 % gain error and a 2 mV offset against the range table.
double softcal_gain() noexcept;
double softcal_offset_V() noexcept;

}  // namespace fake_comedi
