/// @file splits.cc
/// @brief The paper's three train/test settings and their YAML file.
#include "scene/splits.h"

#include <algorithm>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <unordered_set>

#include <yaml-cpp/yaml.h>

#include "scene/capture.h"

namespace p2i::scene {
namespace {

void CheckSequences(const DatasetIndex& dataset, const std::vector<std::string>& sequences) {
  const std::vector<std::string> have = dataset.Sequences();
  for (const std::string& s : sequences) {
    if (std::find(have.begin(), have.end(), s) == have.end()) {
      std::string list;
      for (const std::string& h : have) list += (list.empty() ? "" : ", ") + h;
      throw std::invalid_argument("split: sequence '" + s + "' is not in the dataset (it has: " +
                                  list + ")");
    }
  }
}

std::vector<std::string> IdsOf(const DatasetIndex& dataset,
                               const std::vector<std::string>& sequences) {
  const std::unordered_set<std::string> wanted(sequences.begin(), sequences.end());
  std::vector<std::string> out;
  for (const FrameRef& f : dataset.frames()) {
    if (wanted.count(f.sequence) != 0) out.push_back(f.id);
  }
  return out;
}

}  // namespace

std::string ToString(SplitSetting setting) {
  switch (setting) {
    case SplitSetting::kMissingFrames:
      return "missing_frames";
    case SplitSetting::kAdjacentTrajectory:
      return "adjacent_trajectory";
    case SplitSetting::kCrossTrajectory:
      return "cross_trajectory";
  }
  return "?";
}

SplitSetting SplitSettingFromString(const std::string& name) {
  for (SplitSetting s : {SplitSetting::kMissingFrames, SplitSetting::kAdjacentTrajectory,
                         SplitSetting::kCrossTrajectory}) {
    if (ToString(s) == name) return s;
  }
  throw std::invalid_argument("unknown split setting '" + name +
                              "' (use missing_frames, adjacent_trajectory or cross_trajectory)");
}

std::string EvalSetting::Name() const {
  switch (split) {
    case SplitSetting::kMissingFrames:
      return "a" + std::to_string(held_out);
    case SplitSetting::kAdjacentTrajectory:
      return "b";
    case SplitSetting::kCrossTrajectory:
      return "c";
  }
  return "?";
}

const std::vector<EvalSetting>& PaperSettings() {
  static const std::vector<EvalSetting> all = {
      {SplitSetting::kMissingFrames, 1},      {SplitSetting::kMissingFrames, 3},
      {SplitSetting::kMissingFrames, 10},     {SplitSetting::kMissingFrames, 20},
      {SplitSetting::kAdjacentTrajectory, 0}, {SplitSetting::kCrossTrajectory, 0}};
  return all;
}

EvalSetting EvalSetting::Parse(const std::string& name) {
  for (const EvalSetting& s : PaperSettings())
    if (s.Name() == name) return s;
  throw std::invalid_argument("unknown setting '" + name +
                              "' (allowed: a1, a3, a10, a20 = (a) with N held out, "
                              "b = adjacent trajectory, c = cross trajectory)");
}

bool EvalSetting::operator<(const EvalSetting& other) const {
  if (split != other.split) return static_cast<int>(split) < static_cast<int>(other.split);
  return held_out < other.held_out;
}

bool EvalSetting::operator==(const EvalSetting& other) const {
  return split == other.split && held_out == other.held_out;
}

void Split::Validate() const {
  if (train.empty()) throw std::invalid_argument("split has no training frames");
  std::unordered_set<std::string> seen;
  for (const auto* list : {&train, &test}) {
    for (const std::string& id : *list) {
      if (!seen.insert(id).second) {
        throw std::invalid_argument("split lists frame '" + id +
                                    "' twice (train and test must be disjoint)");
      }
    }
  }
  if (setting == SplitSetting::kMissingFrames && (held_out <= 0 || held_out >= period)) {
    throw std::invalid_argument("split: missing_frames needs 0 < held_out < period");
  }
}

std::string Split::ToYamlString() const {
  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "setting" << YAML::Value << ToString(setting);
  if (setting == SplitSetting::kMissingFrames) {
    out << YAML::Key << "period" << YAML::Value << period;
    out << YAML::Key << "held_out" << YAML::Value << held_out;
  }
  out << YAML::Key << "train_sequences" << YAML::Value << YAML::Flow << train_sequences;
  out << YAML::Key << "test_sequences" << YAML::Value << YAML::Flow << test_sequences;
  out << YAML::Key << "train_count" << YAML::Value << train.size();
  out << YAML::Key << "test_count" << YAML::Value << test.size();
  out << YAML::Key << "train" << YAML::Value << YAML::BeginSeq;
  for (const std::string& id : train) out << YAML::DoubleQuoted << id;
  out << YAML::EndSeq;
  out << YAML::Key << "test" << YAML::Value << YAML::BeginSeq;
  for (const std::string& id : test) out << YAML::DoubleQuoted << id;
  out << YAML::EndSeq;
  out << YAML::EndMap;
  return std::string("# p2i train/test split, see docs/DATASETS.md\n") + out.c_str() + "\n";
}

void Split::ToYamlFile(const std::string& path) const {
  Validate();
  WriteFileAtomic(path, ToYamlString());
}

Split Split::FromYamlString(const std::string& text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const std::exception& e) {
    throw std::invalid_argument("cannot parse split '" + source + "': " + e.what());
  }
  if (!root.IsMap()) throw std::invalid_argument("split '" + source + "' is not a YAML mapping");
  static const std::set<std::string> kKnown = {
      "setting",   "period",     "held_out", "train_sequences", "test_sequences",
      "train_count", "test_count", "train",  "test"};
  for (const auto& kv : root) {
    const std::string key = kv.first.as<std::string>();
    if (kKnown.count(key) == 0) {
      throw std::invalid_argument("split '" + source + "': unknown key '" + key + "'");
    }
  }
  Split s;
  try {
    if (!root["setting"]) throw std::invalid_argument("missing key 'setting'");
    s.setting = SplitSettingFromString(root["setting"].as<std::string>());
    if (root["period"]) s.period = root["period"].as<int>();
    if (root["held_out"]) s.held_out = root["held_out"].as<int>();
    if (root["train_sequences"]) {
      s.train_sequences = root["train_sequences"].as<std::vector<std::string>>();
    }
    if (root["test_sequences"]) {
      s.test_sequences = root["test_sequences"].as<std::vector<std::string>>();
    }
    if (!root["train"] || !root["test"]) throw std::invalid_argument("missing 'train' or 'test'");
    s.train = root["train"].as<std::vector<std::string>>();
    s.test = root["test"].as<std::vector<std::string>>();
    if (s.setting != SplitSetting::kMissingFrames) s.period = s.held_out = 0;
    if (root["train_count"] && root["train_count"].as<size_t>() != s.train.size()) {
      throw std::invalid_argument("train_count does not match the train list (truncated file?)");
    }
    if (root["test_count"] && root["test_count"].as<size_t>() != s.test.size()) {
      throw std::invalid_argument("test_count does not match the test list (truncated file?)");
    }
    s.Validate();
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument("split '" + source + "': " + e.what());
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("split '" + source + "': " + e.what());
  }
  return s;
}

Split Split::FromYamlFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open split file '" + path + "'");
  std::stringstream ss;
  ss << in.rdbuf();
  return FromYamlString(ss.str(), path);
}

bool Split::operator==(const Split& o) const {
  return setting == o.setting && period == o.period && held_out == o.held_out &&
         train_sequences == o.train_sequences && test_sequences == o.test_sequences &&
         train == o.train && test == o.test;
}

std::vector<bool> MissingFramesMask(size_t count, int held_out, int period) {
  if (period <= 0 || held_out <= 0 || held_out >= period) {
    throw std::invalid_argument("missing-frames split needs 0 < held_out (" +
                                std::to_string(held_out) + ") < period (" +
                                std::to_string(period) + ")");
  }
  std::vector<bool> mask(count, false);
  const size_t p = static_cast<size_t>(period), n = static_cast<size_t>(held_out);
  for (size_t i = p; i < count; ++i) {
    mask[i] = (i % p) < n && (i / p) * p + n <= count;
  }
  return mask;
}

Split MakeMissingFramesSplit(const DatasetIndex& dataset, int held_out, int period,
                             const std::vector<std::string>& sequences) {
  Split s;
  s.setting = SplitSetting::kMissingFrames;
  s.period = period;
  s.held_out = held_out;
  s.train_sequences = sequences.empty() ? dataset.Sequences() : sequences;
  CheckSequences(dataset, s.train_sequences);
  s.test_sequences = s.train_sequences;
  for (const std::string& seq : s.train_sequences) {
    // Position within the sequence in time order (the dataset keeps each sequence sorted).
    std::vector<const FrameRef*> frames;
    for (const FrameRef& f : dataset.frames()) {
      if (f.sequence == seq) frames.push_back(&f);
    }
    std::stable_sort(frames.begin(), frames.end(),
                     [](const FrameRef* a, const FrameRef* b) { return a->stamp < b->stamp; });
    const std::vector<bool> mask = MissingFramesMask(frames.size(), held_out, period);
    for (size_t i = 0; i < frames.size(); ++i) {
      (mask[i] ? s.test : s.train).push_back(frames[i]->id);
    }
  }
  s.Validate();
  return s;
}

Split MakeAdjacentTrajectorySplit(const DatasetIndex& dataset, const std::string& train_sequence,
                                  const std::string& test_sequence) {
  if (train_sequence == test_sequence) {
    throw std::invalid_argument("adjacent-trajectory split: train and test sequence are both '" +
                                train_sequence + "'");
  }
  Split s = MakeCrossTrajectorySplit(dataset, {train_sequence}, {test_sequence});
  s.setting = SplitSetting::kAdjacentTrajectory;
  return s;
}

Split MakeCrossTrajectorySplit(const DatasetIndex& dataset,
                               const std::vector<std::string>& train_sequences,
                               const std::vector<std::string>& test_sequences) {
  if (train_sequences.empty() || test_sequences.empty()) {
    throw std::invalid_argument("trajectory split needs at least one train and one test sequence");
  }
  for (const std::string& t : test_sequences) {
    if (std::find(train_sequences.begin(), train_sequences.end(), t) != train_sequences.end()) {
      throw std::invalid_argument("trajectory split: sequence '" + t +
                                  "' is in both the train and the test list");
    }
  }
  CheckSequences(dataset, train_sequences);
  CheckSequences(dataset, test_sequences);
  Split s;
  s.setting = SplitSetting::kCrossTrajectory;
  s.period = 0;
  s.train_sequences = train_sequences;
  s.test_sequences = test_sequences;
  s.train = IdsOf(dataset, train_sequences);
  s.test = IdsOf(dataset, test_sequences);
  s.Validate();
  return s;
}

}  // namespace p2i::scene
