// Chamber logs built in memory for the unit tests.
#pragma once

#include <string>
#include <vector>

#include "thermodrift/io/chamber_log.hpp"

namespace thermodrift::testing {

// A log of one gyro axis and one temperature channel from explicit samples; row i is
// file line i + 2 (after a header).
inline ChamberLog one_axis_log(const std::vector<double>& time, const std::vector<double>& gyro,
                               const std::vector<double>& temperature, const std::string& source = "memory") {
  ChamberLog log;
  log.source = source;
  log.time = time;
  log.gyro_names = {"gyro_x"};
  log.gyro = {gyro};
  log.temperature_names = {"temp"};
  log.temperature = {temperature};
  for (std::size_t i = 0; i < time.size(); ++i) log.line.push_back(i + 2);
  return log;
}

}  // namespace thermodrift::testing
