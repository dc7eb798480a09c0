#include "load_cli.hpp"

namespace metro::apps {

void AddLoadCliOptions(CLI::App* app, LoadCliOptions* o, bool full_scale_flags) {
  app->add_option("--format", o->format,
                  "input format (auto: detected; csv is session.csv in any dialect)")
      ->check(CLI::IsMember({"auto", "csv", "receiver", "euroc", "raw", "phyphox", "sensorlogger",
                             "phone", "ulog", "mcap", "rosbag1", "rosbag2", "dataflash"}))
      ->capture_default_str();
  app->add_option("--topic", o->library.topics,
                  "ULog input: an IMU topic to read (sensor_combined, sensor_accel, sensor_gyro, "
                  "vehicle_imu), each instance one tag, NAME[K] instance K only (default: "
                  "sensor_combined, else sensor_accel and sensor_gyro); MCAP and ROS bags: a "
                  "sensor_msgs/Imu topic, e.g. /imu/data (default: the log's one IMU topic); "
                  "ArduPilot DataFlash: IMU, IMU2, IMU3, or IMU[K] for instance K of an IMU "
                  "message with an I column (default: all); repeatable, each topic one tag");
  app->add_option("--time", o->time,
                  "MCAP and ROS bags: the sample time, header (the message's header.stamp) or "
                  "receive (the time the recorder logged it)")
      ->check(CLI::IsMember({"header", "receive"}))
      ->capture_default_str();
  app->add_option("--time-order", o->time_order,
                  "MCAP, ROS bags, ULog: times out of order or repeated are sorted (repeats after "
                  "the first dropped, both counted in input.notes) or refused")
      ->check(CLI::IsMember({"sort", "refuse"}))
      ->capture_default_str();
  app->add_option("--frame-period-s", o->library.frame_period_s,
                  "receiver frame period in seconds (default 3281/32768 = 0.10013)")
      ->check(CLI::PositiveNumber);
  app->add_flag("--lenient", o->library.lenient,
                "skip malformed rows (counted in input.rejected_rows) instead of stopping");
  app->add_option("--column", o->columns,
                  "map a header name to a canonical column, 'SRC=DST' (SRC= leaves it out); "
                  "repeatable");
  app->add_option("--columns-file", o->columns_file, "a file of SRC=DST mappings, one per line")
      ->check(CLI::ExistingFile);
  app->add_option("--rate-hz", o->library.rate_hz,
                  "a file without a time column: sample k of each tag is at k / R seconds")
      ->check(CLI::PositiveNumber);
  if (full_scale_flags) {
    app->add_option("--accel-fs-g", o->library.accel_fs_g,
                    "raw accelerometer counts: full scale in g (adds ax_g.. beside ax_lsb..)")
        ->check(CLI::PositiveNumber);
    app->add_option("--gyro-fs-dps", o->library.gyro_fs_dps,
                    "raw gyroscope counts: full scale in deg/s (adds gx_dps.. beside gx_lsb..)")
        ->check(CLI::PositiveNumber);
  }
}

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
