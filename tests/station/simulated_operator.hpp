// Test support: a simulated operator at the calibration station, closing the loop in-process.
// The operator moves a SimulatedRawTag (sim/raw_tag.hpp) and watches the guide's events like a
// person at the station: it takes the six faces in its own random order (sometimes skipping
// one), then the pose the guide asks for; holds until the guide says the hold is complete;
// makes too-short holds and knocks at given rates, and sometimes re-seats the tag on the face
// it just took (the guide then says "too close").
#pragma once

#include <algorithm>
#include <deque>
#include <pcg_random.hpp>
#include <random>
#include <string>
#include <vector>

#include "metro/sim/raw_tag.hpp"
#include "metro/station/station.hpp"

namespace metro::station_test {

struct OperatorScript {
  uint64_t seed = 1;
  double short_hold_rate = 0.10;  // Holds cut short (moved on before the guide said so).
  double knock_rate = 0.05;       // Holds knocked.
  double skip_face_rate = 0.2;    // Sessions in which the operator skips a face at first.
  double reseat_rate = 0.05;      // Re-seats after an accepted pose.
  int max_actions = 120;
};

struct OperatorRun {
  std::vector<station::StationEvent> events;
  int short_holds = 0, knocks = 0, reseats = 0, skipped_faces = 0;
  int64_t lines = 0;
};

// Feeds the samples to the station, collecting events; true when the guide stopped.
inline bool FeedSamples(const std::vector<RawTagSample>& samples, station::Station* st,
                        OperatorRun* run) {
  for (const RawTagSample& s : samples) {
    station::RawSample r;
    for (int a = 0; a < 3; ++a) {
      r.accel_lsb[a] = s.counts[a];
      r.gyro_lsb[a] = s.counts[3 + a];
    }
    for (int a = 0; a < 6; ++a) {
      if (s.counts[a] == -32768 || s.counts[a] == 32767) r.saturated = true;
    }
    if (r.saturated) r.saturated_axis = "a count";
    for (station::StationEvent& e : st->Feed(r, ++run->lines)) run->events.push_back(e);
    if (st->Done()) return true;
  }
  return st->Done();
}

inline bool Saw(const OperatorRun& run, size_t from, station::StationEventKind kind) {
  for (size_t i = from; i < run.events.size(); ++i) {
    if (run.events[i].kind == kind) return true;
  }
  return false;
}

// Runs one session until the guide stops (or max_actions).
inline OperatorRun RunOperator(const OperatorScript& script, SimulatedRawTag* tag,
                               station::Station* st) {
  using K = station::StationEventKind;
  OperatorRun run;
  pcg64 rng(script.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<int> faces = {0, 1, 2, 3, 4, 5};
  std::shuffle(faces.begin(), faces.end(), rng);
  std::deque<int> own(faces.begin(), faces.end());
  if (unit(rng) < script.skip_face_rate) {
    own.pop_back();  // The guide will ask for it.
    ++run.skipped_faces;
  }
  const std::vector<station::ProtocolPose> poses =
      station::ProtocolPoses(station::Protocol::kSixFace);
  std::vector<RawTagSample> buf;
  for (int action = 0; action < script.max_actions && !st->Done(); ++action) {
    Eigen::Vector3d target;
    if (!own.empty()) {
      target = poses[static_cast<size_t>(own.front())].up_body;
      own.pop_front();
    } else {
      const station::StationView v = st->View();
      if (v.next_pose.empty()) {
        buf.clear();
        tag->Move(-tag->UpBody(), 1.0, &buf);  // Nothing left to take: lifts the tag off.
        FeedSamples(buf, st, &run);
        break;
      }
      target = v.next_up;
    }
    buf.clear();
    tag->Move(target, 1.2 + 1.3 * unit(rng), &buf);
    if (FeedSamples(buf, st, &run)) return run;
    const double roll = unit(rng);
    if (roll < script.short_hold_rate) {
      ++run.short_holds;
      buf.clear();
      tag->Hold(0.5 + 0.5 * unit(rng), &buf);  // Moves on too early: the guide rejects it.
      if (FeedSamples(buf, st, &run)) return run;
      continue;
    }
    const size_t from = run.events.size();
    if (roll < script.short_hold_rate + script.knock_rate) {
      ++run.knocks;
      buf.clear();
      tag->Hold(0.4 + 0.8 * unit(rng), &buf);
      tag->Knock(0.3 + 0.7 * unit(rng), &buf);
      if (FeedSamples(buf, st, &run)) return run;
    }
    // Hold until the guide says complete (or too close), in steps of 0.1 s, 40 s at most.
    const size_t watch = run.events.size();
    for (int step = 0; step < 400; ++step) {
      buf.clear();
      tag->Hold(0.1, &buf);
      if (FeedSamples(buf, st, &run)) return run;
      if (Saw(run, watch, K::kHoldComplete) || Saw(run, from, K::kTooClose)) break;
    }
    buf.clear();
    tag->Hold(0.3, &buf);
    if (FeedSamples(buf, st, &run)) return run;
    if (unit(rng) < script.reseat_rate) {
      ++run.reseats;
      buf.clear();
      tag->Reseat(1.0, &buf);
      tag->Hold(1.0, &buf);
      if (FeedSamples(buf, st, &run)) return run;
    }
  }
  return run;
}

}  // namespace metro::station_test
