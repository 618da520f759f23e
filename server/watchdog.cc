#include "server/watchdog.h"

namespace tetrefine::server {

Watchdog::Watchdog() : thread_([this] { Loop(); }) {}

Watchdog::~Watchdog() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    stopping_ = true;
  }
  changed_.notify_all();
  thread_.join();
}

Watchdog::Id Watchdog::Schedule(Clock::time_point when, std::function<void()> callback) {
  Id id;
  {
    std::lock_guard<std::mutex> lock(mu_);
    id = next_id_++;
    pending_.emplace(std::make_pair(when, id), std::move(callback));
    when_.emplace(id, when);
  }
  changed_.notify_all();
  return id;
}

void Watchdog::Cancel(Id id) {
  std::unique_lock<std::mutex> lock(mu_);
  if (auto it = when_.find(id); it != when_.end()) {
    pending_.erase({it->second, id});
    when_.erase(it);
    return;
  }
  if (std::this_thread::get_id() == thread_.get_id()) return;
  changed_.wait(lock, [&] { return running_ != id; });
}

void Watchdog::Loop() {
  std::unique_lock<std::mutex> lock(mu_);
  while (!stopping_) {
    if (pending_.empty()) {
      changed_.wait(lock);
      continue;
    }
    const auto first = pending_.begin();
    const Clock::time_point when = first->first.first;
    if (Clock::now() < when) {
      changed_.wait_until(lock, when);
      continue;
    }
    const Id id = first->first.second;
    std::function<void()> callback = std::move(first->second);
    pending_.erase(first);
    when_.erase(id);
    running_ = id;
    lock.unlock();
    callback();
    callback = nullptr;  // whatever it captured goes before Cancel may return
    lock.lock();
    running_ = 0;
    changed_.notify_all();
  }
}

}  // namespace tetrefine::server
