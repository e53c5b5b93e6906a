#pragma once
// What the integer codes of the logged messages mean: for each coded field of each message type,
// its values and names, taken from the constants lcm-gen generates from lcmtypes/*.lcm (a
// constant's name, lower case without its prefix: command_block_t::MODE_LINEAR -> 1 "linear").
// CSV, HDF5 and MAT exports write these next to the columns, so a lab reads "mode 2" as "mem"
// without the .lcm files at hand. The one home of these tables: a new constant is one line here.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace hystloop::report {

struct Code {
  std::int64_t value = 0;
  std::string name;  // "linear"
};

struct CodeLegend {
  std::string_view type_name;  // "hystloop.command_block_t"
  std::string_view field;      // "mode", as the field is called in the .lcm and in the exports
  std::vector<Code> codes;
  bool bits = false;  // the field ORs the codes (flags) instead of holding one of them

  // "0=off,1=linear,2=mem"; for bits "bits: 1=saturated,2=safe_state (0=none)".
  std::string text() const;
};

// Every coded field of every hystloop message type.
const std::vector<CodeLegend>& code_legends();

// The legend of `field` of the type named `type_name`, or nullptr if the field is not coded.
const CodeLegend* find_code_legend(std::string_view type_name, std::string_view field);

}  // namespace hystloop::report
