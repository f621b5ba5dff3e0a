/// @file distributed.cc
/// @brief DistributedOptions::Validate and DataParallel on c10d TCPStore + ProcessGroupGloo.
#ifndef USE_C10D_GLOO  // ProcessGroupGloo.hpp is guarded by it (Torch's CMake defines it)
#define USE_C10D_GLOO 1
#endif
#include "model/distributed.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <mutex>
#include <stdexcept>

#include <nlohmann/json.hpp>
#include <torch/csrc/distributed/c10d/ProcessGroupGloo.hpp>
#include <torch/csrc/distributed/c10d/TCPStore.hpp>

#include "model/checkpoint.h"
#include "model/data_parallel.h"

namespace p2i::model {
namespace {

bool SplitHostPort(const std::string& s, std::string* host, int* port) {
  const auto colon = s.rfind(':');
  if (colon == std::string::npos || colon == 0) return false;
  *host = s.substr(0, colon);
  char* end = nullptr;
  const long p = std::strtol(s.c_str() + colon + 1, &end, 10);
  if (*end != '\0' || p < 1 || p > 65535) return false;
  *port = static_cast<int>(p);
  return true;
}

}  // namespace

bool IsHostPort(const std::string& s) {
  std::string host;
  int port = 0;
  return SplitHostPort(s, &host, &port);
}

void DistributedOptions::Validate() const {
  if (world_size < 1) throw std::invalid_argument("--world-size must be >= 1");
  if (rank < 0 || rank >= world_size)
    throw std::invalid_argument("--rank " + std::to_string(rank) + " must be in 0.." +
                                std::to_string(world_size - 1) + " (--world-size " +
                                std::to_string(world_size) + ")");
  if (!(timeout_s > 0)) throw std::invalid_argument("--dist-timeout must be > 0 seconds");
  if (world_size > 1) {
    std::string host;
    int port = 0;
    if (!SplitHostPort(master, &host, &port))
      throw std::invalid_argument("--master '" + master + "' must be HOST:PORT (rank 0's address "
                                  "and a free port, e.g. 127.0.0.1:29500)");
  }
}

struct DataParallel::Impl {
  c10::intrusive_ptr<c10d::Store> store;
  c10::intrusive_ptr<c10d::ProcessGroupGloo> group;
};

DataParallel::DataParallel(const DistributedOptions& o) : impl_(std::make_unique<Impl>()), options_(o) {
  std::string host;
  int port = 0;
  SplitHostPort(o.master, &host, &port);
  const auto timeout = std::chrono::milliseconds(static_cast<int64_t>(o.timeout_s * 1000));
  try {
    c10d::TCPStoreOptions so;
    so.port = static_cast<uint16_t>(port);
    so.isServer = o.rank == 0;
    so.numWorkers = static_cast<size_t>(o.world_size);
    so.waitWorkers = true;
    so.timeout = timeout;
    impl_->store = c10::make_intrusive<c10d::TCPStore>(host, so);
    auto go = c10d::ProcessGroupGloo::Options::create(timeout);
    std::string address = o.address;
    if (address.empty() && (host == "127.0.0.1" || host == "localhost")) address = "127.0.0.1";
    go->devices.push_back(address.empty()
                              ? c10d::ProcessGroupGloo::createDefaultDevice()
                              : c10d::ProcessGroupGloo::createDeviceForHostname(address));
    go->threads = 1;
    impl_->group = c10::make_intrusive<c10d::ProcessGroupGloo>(impl_->store, o.rank,
                                                               o.world_size, go);
  } catch (const std::exception& e) {
    throw std::runtime_error("data-parallel training: rank " + std::to_string(o.rank) + " of " +
                             std::to_string(o.world_size) + " could not meet the others at " +
                             o.master + " within " + std::to_string(o.timeout_s) +
                             " s (start every rank with the same --world-size and --master; "
                             "rank 0 listens there): " + e.what());
  }
}

DataParallel::~DataParallel() = default;

std::shared_ptr<DataParallel> DataParallel::For(const DistributedOptions& options) {
  if (!options.Enabled()) return nullptr;
  options.Validate();
  // One group per (master, rank, world_size), made once. The rendezvous blocks until every
  // rank has arrived, so only that key's entry is locked meanwhile: several ranks of one
  // process (threads, e.g. tests) can meet each other.
  struct Entry {
    std::mutex mutex;
    std::shared_ptr<DataParallel> group;
  };
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<Entry>> groups;
  const std::string key = options.master + "#" + std::to_string(options.rank) + "/" +
                          std::to_string(options.world_size);
  std::shared_ptr<Entry> entry;
  {
    std::lock_guard<std::mutex> lock(mutex);
    auto& e = groups[key];
    if (!e) e = std::make_shared<Entry>();
    entry = e;
  }
  std::lock_guard<std::mutex> lock(entry->mutex);
  if (!entry->group) entry->group.reset(new DataParallel(options));
  return entry->group;
}

void DataParallel::Lost(const std::string& during, const std::exception& e) const {
  throw std::runtime_error("data-parallel training: rank " + std::to_string(options_.rank) +
                           " lost contact with the other ranks during " + during +
                           " (a rank died, was stopped, or the network failed; timeout " +
                           std::to_string(options_.timeout_s) + " s). Rank 0's last checkpoint "
                           "is intact: restart every rank with --resume (p2i train; trainer "
                           "nodes resume from it by themselves). Cause: " + e.what());
}

void DataParallel::Broadcast(const std::vector<torch::Tensor>& tensors) {
  torch::NoGradGuard no_grad;
  try {
    for (const auto& t : tensors) {
      std::vector<at::Tensor> one{t.detach()};
      impl_->group->broadcast(one)->wait();
    }
  } catch (const std::exception& e) {
    Lost("the parameter broadcast", e);
  }
}

bool DataParallel::AverageGradients(const std::vector<torch::Tensor>& params, bool diverged) {
  torch::NoGradGuard no_grad;
  std::vector<torch::Tensor> grads;
  for (const auto& p : params)
    if (p.grad().defined()) grads.push_back(p.grad());
  std::vector<torch::Tensor> flat_parts;
  for (const auto& g : grads) flat_parts.push_back(g.reshape({-1}).to(torch::kFloat));
  // The divergence verdict: > 0 after the sum when any rank's loss diverged.
  flat_parts.push_back(torch::tensor({diverged ? 1.0f : 0.0f}));
  torch::Tensor flat = torch::cat(flat_parts);
  const auto t0 = std::chrono::steady_clock::now();
  try {
    std::vector<at::Tensor> one{flat};
    impl_->group->allreduce(one)->wait();
  } catch (const std::exception& e) {
    Lost("the gradient all-reduce", e);
  }
  allreduce_ms_.push_back(
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  last_bytes_ = flat.numel() * static_cast<int64_t>(flat.element_size());
  allreduce_bytes_.push_back(last_bytes_);
  const int64_t n_grads = flat.numel() - 1;
  // The flag is its own element: NaN gradients of a diverged rank do not reach it.
  const bool any_diverged = flat[n_grads].item<float>() > 0.5f;
  if (any_diverged) return true;  // the caller rolls back; these gradients are never applied
  flat.div_(static_cast<double>(options_.world_size));
  int64_t offset = 0;
  for (auto& g : grads) {
    const int64_t n = g.numel();
    g.copy_(flat.slice(0, offset, offset + n).view_as(g));
    offset += n;
  }
  return false;
}

bool DataParallel::AverageGradients(torch::optim::Optimizer& optimizer, bool diverged) {
  std::vector<torch::Tensor> params;
  for (auto& group : optimizer.param_groups())
    for (auto& p : group.params()) params.push_back(p);
  return AverageGradients(params, diverged);
}

void DataParallel::Start(const int* phase1_step, const int* phase2_step, Networks& nets) {
  Agree(*phase1_step, "the phase-1 step to start from");
  Agree(*phase2_step, "the phase-2 step to start from");
  std::vector<torch::Tensor> all;
  for (torch::nn::Module* m : std::vector<torch::nn::Module*>{
           nets.g.get(), nets.d ? nets.d.get() : nullptr, nets.e ? nets.e.get() : nullptr,
           nets.g_ema ? nets.g_ema.get() : nullptr}) {
    if (!m) continue;
    for (auto& p : m->parameters()) all.push_back(p);
    for (auto& b : m->buffers()) all.push_back(b);
  }
  Broadcast(all);
}

bool DataParallel::Any(bool flag) {
  torch::Tensor t = torch::tensor({flag ? 1.0f : 0.0f});
  try {
    std::vector<at::Tensor> one{t};
    c10d::AllreduceOptions o;
    o.reduceOp = c10d::ReduceOp::MAX;
    impl_->group->allreduce(one, o)->wait();
  } catch (const std::exception& e) {
    Lost("the stop check", e);
  }
  return t.item<float>() > 0.5f;
}

void DataParallel::Agree(int64_t value, const std::string& what) {
  torch::Tensor lo = torch::tensor({static_cast<double>(value)}, torch::kDouble);
  torch::Tensor hi = lo.clone();
  try {
    std::vector<at::Tensor> a{lo}, b{hi};
    c10d::AllreduceOptions omin, omax;
    omin.reduceOp = c10d::ReduceOp::MIN;
    omax.reduceOp = c10d::ReduceOp::MAX;
    impl_->group->allreduce(a, omin)->wait();
    impl_->group->allreduce(b, omax)->wait();
  } catch (const std::exception& e) {
    Lost("the check of " + what, e);
  }
  if (lo.item<double>() != hi.item<double>())
    throw std::runtime_error("data-parallel training: the ranks disagree on " + what + " (rank " +
                             std::to_string(options_.rank) + " has " + std::to_string(value) +
                             ", the ranks range " + std::to_string(lo.item<double>()) + ".." +
                             std::to_string(hi.item<double>()) +
                             "): give every rank the same checkpoint (rank 0's) and config");
}

std::vector<double> DataParallel::Min(const std::vector<double>& values, const std::string& what) {
  if (values.empty()) return values;
  torch::Tensor t = torch::tensor(values, torch::kDouble);
  try {
    std::vector<at::Tensor> one{t};
    c10d::AllreduceOptions o;
    o.reduceOp = c10d::ReduceOp::MIN;
    impl_->group->allreduce(one, o)->wait();
  } catch (const std::exception& e) {
    Lost(what, e);
  }
  const double* p = t.data_ptr<double>();
  return std::vector<double>(p, p + values.size());
}

std::string DataParallel::BroadcastBytes(const std::string& bytes, const std::string& what) {
  try {
    torch::Tensor size = torch::tensor({static_cast<int64_t>(bytes.size())}, torch::kLong);
    std::vector<at::Tensor> one{size};
    impl_->group->broadcast(one)->wait();
    const int64_t n = size.item<int64_t>();
    if (n == 0) return std::string();
    torch::Tensor data = IsWriter() ? torch::from_blob(const_cast<char*>(bytes.data()), {n},
                                                       torch::kUInt8).clone()
                                    : torch::empty({n}, torch::kUInt8);
    std::vector<at::Tensor> payload{data};
    impl_->group->broadcast(payload)->wait();
    return std::string(reinterpret_cast<const char*>(data.data_ptr<uint8_t>()),
                       static_cast<size_t>(n));
  } catch (const std::exception& e) {
    Lost(what, e);
  }
}

namespace {

DataParallel& GroupOf(const DistributedOptions& options) {
  if (!options.Enabled())
    throw std::logic_error("data-parallel collective called with world_size 1");
  return *DataParallel::For(options);
}

}  // namespace

int64_t MinOverRanks(const DistributedOptions& options, int64_t value) {
  return static_cast<int64_t>(
      GroupOf(options).Min({static_cast<double>(value)}, "the ranks' poll between rounds")[0]);
}

std::string BroadcastFromRankZero(const DistributedOptions& options, const std::string& bytes) {
  return GroupOf(options).BroadcastBytes(bytes, "the broadcast of rank 0's checkpoint");
}

void DataParallel::WriteStats(const std::string& dir) const {
  std::vector<double> ms = allreduce_ms_;
  std::sort(ms.begin(), ms.end());
  double sum = 0;
  for (double m : ms) sum += m;
  // The distinct all-reduce sizes (one per optimiser: G, D, ENET) and the total, so the bytes
  // per training step are total / steps (bench/dp_bench.sh).
  std::vector<int64_t> sizes = allreduce_bytes_;
  std::sort(sizes.begin(), sizes.end());
  sizes.erase(std::unique(sizes.begin(), sizes.end()), sizes.end());
  int64_t total = 0;
  for (int64_t b : allreduce_bytes_) total += b;
  nlohmann::json j{{"rank", options_.rank},
                   {"allreduce_bytes_total", total},
                   {"allreduce_sizes_bytes", sizes},
                   {"world_size", options_.world_size},
                   {"allreduce_calls", ms.size()},
                   {"bytes_per_allreduce", last_bytes_},
                   {"allreduce_ms_mean", ms.empty() ? 0.0 : sum / ms.size()},
                   {"allreduce_ms_p50", ms.empty() ? 0.0 : ms[ms.size() / 2]},
                   {"allreduce_ms_max", ms.empty() ? 0.0 : ms.back()}};
  const std::string path = dir + "/distributed.rank" + std::to_string(options_.rank) + ".json";
  std::ofstream(path + ".tmp") << j.dump(2) << "\n";
  std::rename((path + ".tmp").c_str(), path.c_str());
}

}  // namespace p2i::model
