// Any bytes as a chamber log: the reader either returns a log or throws one of the
// library's typed errors; anything else (a crash, another exception) is a bug.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <sstream>
#include <string>

#include "thermodrift/error.hpp"
#include "thermodrift/io/bursts.hpp"
#include "thermodrift/io/chamber_log.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  // The first byte picks how the columns are named, so both paths are explored.
  thermodrift::LogSpec spec;
  if (size > 0 && (data[0] & 1)) {
    spec.rate_hz = 1.0;
    spec.gyro_columns = {"2", "3"};
    spec.temperature_columns = {"1"};
  } else {
    spec.gyro_columns = {"gyro_x"};
    spec.temperature_columns = {"temp"};
  }
  if (size > 0 && (data[0] & 2)) spec.csv.garbled_per_thousand = 0;
  // Further bits: a time unit for numeric stamps (ISO 8601 ones need none), the spike
  // filter, and the burst collapse that fit and evaluate apply after reading.
  if (size > 0 && (data[0] & 4)) spec.time_unit = (data[0] & 8) ? thermodrift::TimeUnit::ns : thermodrift::TimeUnit::ms;
  if (size > 0 && (data[0] & 16)) spec.despike = thermodrift::DespikeOptions{};
  try {
    thermodrift::CsvReader reader(std::make_unique<std::istringstream>(text), "fuzz.csv", spec.csv);
    const auto log = thermodrift::read_chamber_log(reader, spec);
    (void)log.rows();
    const auto collapsed = thermodrift::collapse_if_bursts(log, 200);
    (void)collapsed.rows();
  } catch (const thermodrift::Error&) {
  }
  return 0;
}
