// Any bytes as libsvm-format data: a data set or a typed error, nothing else.
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "thermodrift/error.hpp"
#include "thermodrift/io/libsvm_reader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream input(std::string(reinterpret_cast<const char*>(data), size));
  try {
    const auto set = thermodrift::read_libsvm(input, "fuzz.libsvm");
    (void)set.samples.rows();
  } catch (const thermodrift::Error&) {
  }
  return 0;
}
