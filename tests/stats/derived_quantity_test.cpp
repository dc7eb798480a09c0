// A derived quantity asked for by name whose inputs the session holds only in part: the
// message names the inputs the tag has and those it lacks (docs/formats.md: yaw_deg,
// pitch_deg, roll_deg come from the whole quaternion qw, qx, qy, qz).
#include "metro/stats/derived_quantity.hpp"

#include <catch2/catch.hpp>
#include <string>
#include <vector>

#include "metro/stats/session_type_a.hpp"

namespace metro {
namespace {

Tag TagWith(int sensor, const std::vector<std::string>& names) {
  Tag tag;
  tag.sensor = sensor;
  for (int i = 0; i < 10; ++i) {
    tag.t_s.push_back(0.1 * i);
    tag.line.push_back(static_cast<uint32_t>(i + 2));
  }
  for (const std::string& n : names) {
    Quantity q;
    q.name = n;
    q.unit = "1";
    q.values.assign(tag.t_s.size(), 0.5);
    tag.quantities.push_back(q);
  }
  return tag;
}

TEST_CASE("The Euler angles are derived from the whole quaternion", "[stats][derived]") {
  const std::vector<std::string> quat = {"qw", "qx", "qy", "qz"};
  CHECK(DerivationInputs("yaw_deg") == quat);
  CHECK(DerivationInputs("pitch_deg") == quat);
  CHECK(DerivationInputs("roll_deg") == quat);
  for (const char* name : {"temp_c", "gx_dps", "qw", "table_angle_deg", "yaw", ""}) {
    INFO(name);
    CHECK(DerivationInputs(name).empty());
  }
}

TEST_CASE("Part of the quaternion: the missing columns are named", "[stats][derived]") {
  const Tag half = TagWith(1, {"qw", "qx", "temp_c"});
  CHECK(MissingDerivationInputs(half, "yaw_deg") ==
        "yaw_deg is derived from qw, qx, qy, qz; the session has qw, qx; missing qy, qz");
  CHECK(MissingDerivationInputs(half, "roll_deg") ==
        "roll_deg is derived from qw, qx, qy, qz; the session has qw, qx; missing qy, qz");
  // Family order, whatever the order of the columns.
  CHECK(MissingDerivationInputs(TagWith(1, {"qz", "qx", "qy"}), "pitch_deg") ==
        "pitch_deg is derived from qw, qx, qy, qz; the session has qx, qy, qz; missing qw");
  // Nothing to say: no quaternion at all, the whole quaternion, or a quantity not derived.
  CHECK_FALSE(MissingDerivationInputs(TagWith(1, {"temp_c"}), "yaw_deg"));
  CHECK_FALSE(MissingDerivationInputs(TagWith(1, {"qw", "qx", "qy", "qz"}), "yaw_deg"));
  CHECK_FALSE(MissingDerivationInputs(half, "temp_c"));
  CHECK_FALSE(MissingDerivationInputs(half, "qy"));

  // A session: its one tag is "the session"; of several, the tag is named.
  Session one;
  one.tags = {half};
  CHECK(MissingDerivationInputs(one, "yaw_deg") ==
        "yaw_deg is derived from qw, qx, qy, qz; the session has qw, qx; missing qy, qz");
  Session two;
  two.tags = {TagWith(1, {"temp_c"}), TagWith(2, {"qy"})};
  CHECK(MissingDerivationInputs(two, "yaw_deg") ==
        "yaw_deg is derived from qw, qx, qy, qz; sensor 2 has qy; missing qw, qx, qz");
  Session none;
  none.tags = {TagWith(1, {"temp_c"}), TagWith(2, {"gz_dps"})};
  CHECK_FALSE(MissingDerivationInputs(none, "yaw_deg"));
}

TEST_CASE("A --quantity of a derived angle with part of the quaternion names the missing columns",
          "[stats][derived]") {
  Session s;
  s.path = "half.csv";
  s.tags = {TagWith(1, {"qw", "qx"})};
  SessionTypeAOptions o;
  o.quantities = {"yaw_deg"};
  Result<SessionTypeA> r = EvaluateSessionTypeA(s, o);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().ToString() ==
        "half.csv: --quantity yaw_deg: no such quantity in the session: yaw_deg is derived from "
        "qw, qx, qy, qz; the session has qw, qx; missing qy, qz");
  // Without any quaternion column the message lists the quantities, as before.
  s.tags = {TagWith(1, {"temp_c"})};
  r = EvaluateSessionTypeA(s, o);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().ToString() ==
        "half.csv: --quantity yaw_deg: no such quantity in the session (quantities: temp_c)");
}

}  // namespace
}  // namespace metro
