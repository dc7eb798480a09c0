#include "load_cli.hpp"

namespace metro::apps {

Status MakeLoadOptions(const LoadCliOptions& o, LoadOptions* load) {
  if (!ParseSessionFormat(o.format, &load->format)) {
    return MakeError("--format " + o.format + ": unknown format");
  }
  load->lenient = o.library.lenient;
  load->frame_period_s = o.library.frame_period_s;
  load->rate_hz = o.library.rate_hz;
  load->accel_fs_g = o.library.accel_fs_g;
  load->gyro_fs_dps = o.library.gyro_fs_dps;
  load->topics = o.library.topics;
  load->ros_time =
      o.time == "receive" ? LoadOptions::RosTime::kReceive : LoadOptions::RosTime::kHeader;
  load->time_order =
      o.time_order == "refuse" ? LoadOptions::TimeOrder::kRefuse : LoadOptions::TimeOrder::kSort;
  load->column_map.clear();
  if (!o.columns_file.empty()) {
    auto file = LoadColumnMappings(o.columns_file);
    if (!file.ok()) return file.error();
    load->column_map = std::move(file).value();
  }
  // --column after the file: a later mapping of the same name wins.
  for (const std::string& spec : o.columns) {
    auto m = ParseColumnMapping(spec);
    if (!m.ok()) return m.error();
    load->column_map.push_back(std::move(m).value());
  }
  return Status::Ok();
}

}  // namespace metro::apps
