#pragma once
// A CSV file refused: the file, the line (1-based; 0 when the file could not be read at all) and
// what is wrong, as "data.csv:7: column 'u': expected a number, got 'abc'". Every CSV reader of
// the product (hystloop-identify's samples, hystloop-model's columns) throws it.

#include <cstddef>
#include <stdexcept>
#include <string>
#include <utility>

namespace hystloop {

class CsvError : public std::runtime_error {
 public:
  CsvError(std::string file, std::size_t line, const std::string& message)
      : std::runtime_error(file + ":" + std::to_string(line) + ": " + message), file_(std::move(file)), line_(line) {}
  std::size_t line() const noexcept { return line_; }
  const std::string& file() const noexcept { return file_; }

 private:
  std::string file_;
  std::size_t line_;
};

}  // namespace hystloop
