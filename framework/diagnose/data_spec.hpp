// The YAML form of a lab data-file description (framework/io/data_file.hpp),
// written where a run file names its data:
//   data:
//     file: O-ring_3bar.csv          # beside the run file
//     separator: whitespace          # comma | semicolon | tab | whitespace
//     header: no                     # yes | no
//     skip_rows: 15
//     decimal: "."                   # "." | ","
//     thousands: none                # none | "." | "," | "'" | " "
//     columns:                       # pneumo's name: column number or header name, unit
//       t: {column: 1, unit: ms}
//       F: {column: 4, unit: N, scale: 46.5}   # raw volts * N/V
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>

#include "framework/io/data_file.hpp"

namespace pneumo::diagnose {

// `node` is the map under `data:` in `yaml_file`; spec.file is left as
// written (the caller resolves and checks it). InputError at file:line for
// an unknown key, a bad separator or mark, a column without number or name.
DataFileSpec data_spec_from_yaml(const std::string& yaml_file, const YAML::Node& node);

}  // namespace pneumo::diagnose
