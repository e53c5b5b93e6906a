// libFuzzer target: any bytes as a recorded-samples CSV (hystloop-identify's input). The reader
// returns a table or refuses with a CsvError naming the line; it never crashes or reads out of bounds.
#include <cstddef>
#include <cstdint>
#include <exception>
#include <sstream>
#include <string>

#include "ident/sample_csv.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace hystloop;
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    const SampleTable table = parse_sample_csv(in, "fuzz.csv");
    (void)split_experiments(table);
  } catch (const std::exception&) {  // CsvError: a refusal naming the line
  }
  return 0;
}
