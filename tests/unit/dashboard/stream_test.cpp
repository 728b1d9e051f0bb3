// The push stream: a client gets a hello with the cell, then the live events
// it asked for; 20 clients are served at once and one that stops reading
// loses its oldest events (counted) without slowing the other 19; a client
// that accepts nothing for the stall timeout is disconnected.

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <thread>
#include <vector>

#include "dashboard_fixture.hpp"
#include "smc/dashboard/drop_oldest_queue.hpp"

using namespace smc::test;
using namespace std::chrono_literals;

namespace {

google::protobuf::Value parse_json(const std::string& text) {
  google::protobuf::Value v;
  const auto st = google::protobuf::util::JsonStringToMessage(text, &v);
  EXPECT_TRUE(st.ok()) << st.message() << " in " << text.substr(0, 200);
  return v;
}

const google::protobuf::Value& field(const google::protobuf::Value& v, const std::string& k) {
  static const google::protobuf::Value kNull;
  const auto& f = v.struct_value().fields();
  auto it = f.find(k);
  return it == f.end() ? kNull : it->second;
}

google::protobuf::Value stats(uint16_t port) {
  return parse_json(http(port, "GET", "/api/stats").body);
}

size_t stream_count(uint16_t port) {
  return static_cast<size_t>(field(stats(port), "streams").list_value().values_size());
}

void publish_batch(CellSide& cell, const std::string& mill, uint64_t seq) {
  smc_data_ForceBatch b{};
  smc::wire::set_string(b.machine_id, mill);
  b.first_sample_time_ns = seq;
  b.sample_period_ns = 500000;
  b.decimation = 1;
  b.count = 128;
  for (int i = 0; i < 128; ++i) {
    b.f_y_n[i] = 100.25f + static_cast<float>(i);
    b.f_z_n[i] = -50.5f - static_cast<float>(i);
  }
  cell.batches.write(b);
}

}  // namespace

TEST(DropOldestQueue, KeepsTheNewestAndCountsWhatItDropped) {
  smc::dashboard::DropOldestQueue<int> q(3);
  EXPECT_FALSE(q.push(1));
  EXPECT_FALSE(q.push(2));
  EXPECT_FALSE(q.push(3));
  EXPECT_TRUE(q.push(4));
  EXPECT_TRUE(q.push(5));
  EXPECT_EQ(q.dropped(), 2u);
  EXPECT_EQ(q.size(), 3u);
  EXPECT_EQ(q.pop(), 3);
  EXPECT_EQ(q.pop(), 4);
  EXPECT_EQ(q.pop(), 5);
  EXPECT_TRUE(q.empty());
}

TEST(DashboardStream, HelloThenTheEventsOfTheMillsAsked) {
  DashboardFixture f;
  ASSERT_TRUE(f.make_mill("mill-a"));
  ASSERT_TRUE(f.make_mill("mill-b"));
  SseClient all(f.port(), "/api/stream");
  SseClient only_a(f.port(), "/api/stream?mill=mill-a");
  ASSERT_EQ(all.head().status, 200);
  EXPECT_EQ(all.head().header("content-type"), "text/event-stream; charset=utf-8");
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  auto hello = all.next_named("hello", deadline);
  ASSERT_TRUE(hello);
  EXPECT_EQ(field(field(parse_json(hello->data), "cell"), "mills").list_value().values_size(), 2);
  ASSERT_TRUE(only_a.next_named("hello", deadline));

  // b then a: the filtered client's next summary must be a's.
  f.cell().summary("mill-b", 1);
  f.cell().summary("mill-a", 2, 250.f);
  auto s = all.next_named("summary", deadline);
  ASSERT_TRUE(s);
  EXPECT_EQ(field(parse_json(s->data), "machine_id").string_value(), "mill-b");
  auto sa = only_a.next_named("summary", deadline);
  ASSERT_TRUE(sa);
  const auto a = parse_json(sa->data);
  EXPECT_EQ(field(a, "machine_id").string_value(), "mill-a");
  EXPECT_EQ(field(a, "f_y_peak_n").number_value(), 250.0);
  EXPECT_GT(field(a, "src_unix_ms").number_value(), 1.6e12);  // DDS source time, for latency

  // Raw batches only for clients that asked for them.
  SseClient raw(f.port(), "/api/stream?mill=mill-a&raw=1");
  ASSERT_TRUE(raw.next_named("hello", deadline));
  ASSERT_EQ(stream_count(f.port()), 3u);
  publish_batch(f.cell(), "mill-a", 42);
  f.cell().situation("mill-a", 2, 3, 9);  // reliable: arrives even if the batch were lost
  auto first = raw.next(deadline);
  ASSERT_TRUE(first);
  if (first->event == "batch") {
    EXPECT_EQ(field(parse_json(first->data), "f_y_n").list_value().values_size(), 128);
  }
  ASSERT_TRUE(only_a.next_named("situation", deadline));
  // The unfiltered, non-raw client: its next events skip the batch.
  auto next = all.next(deadline);
  ASSERT_TRUE(next);
  EXPECT_NE(next->event, "batch");
}

TEST(DashboardStream, TwentyClientsAndOneThatStopsReadingDoesNotSlowTheOthers) {
  smc::dashboard::Options o;
  o.stream_queue_events = 64;
  o.stream_send_buffer = 8192;
  DashboardFixture f(true, o);
  ASSERT_TRUE(f.make_mill("mill-s"));
  constexpr int kClients = 20;
  constexpr uint32_t kMarker = 4242;

  // Client 0 sends its request and then never reads (tiny receive buffer).
  SseClient stalled(f.port(), "/api/stream?raw=1", 4096);
  std::vector<std::unique_ptr<SseClient>> readers;
  for (int i = 1; i < kClients; ++i) {
    readers.push_back(std::make_unique<SseClient>(f.port(), "/api/stream?raw=1"));
    ASSERT_TRUE(readers.back()->next_named("hello", std::chrono::steady_clock::now() + 10s));
  }
  ASSERT_TRUE(eventually([&] { return stream_count(f.port()) == kClients; }));

  std::atomic<int> done{0};
  std::vector<std::chrono::steady_clock::time_point> marker_at(readers.size());
  std::vector<uint64_t> batches(readers.size(), 0);
  std::vector<std::thread> threads;
  for (size_t i = 0; i < readers.size(); ++i) {
    threads.emplace_back([&, i] {
      const auto deadline = std::chrono::steady_clock::now() + 30s;
      while (auto e = readers[i]->next(deadline)) {
        if (e->event == "batch") ++batches[i];
        if (e->event == "situation" &&
            field(parse_json(e->data), "sequence_number").number_value() == kMarker) {
          marker_at[i] = std::chrono::steady_clock::now();
          break;
        }
      }
      ++done;
    });
  }

  // Raw force until the dashboard has broadcast 600 batches (about 1.5 MB
  // per client; far more than the stalled client's queue and socket hold),
  // then a reliable marker.
  uint64_t k = 0;
  ASSERT_TRUE(eventually(
      [&] {
        for (int i = 0; i < 20; ++i) publish_batch(f.cell(), "mill-s", k++);
        return field(stats(f.port()), "events_broadcast").number_value() >= 600;
      },
      20s));
  const auto marker_sent = std::chrono::steady_clock::now();
  f.cell().situation("mill-s", 2, 3, kMarker);
  for (auto& t : threads) t.join();

  for (size_t i = 0; i < readers.size(); ++i) {
    ASSERT_NE(marker_at[i], std::chrono::steady_clock::time_point{}) << "reader " << i;
    EXPECT_LT(marker_at[i] - marker_sent, 3s) << "reader " << i << " was held up";
    EXPECT_EQ(batches[i], batches[0]) << "every reader gets every batch the server sent";
  }
  // The server's view: the stalled client dropped events, nobody else did.
  const auto st = stats(f.port());
  int stalled_clients = 0;
  for (const auto& s : field(st, "streams").list_value().values()) {
    if (field(s, "dropped").number_value() > 0) {
      ++stalled_clients;
      EXPECT_LE(field(s, "queued").number_value(), 64);
    }
  }
  EXPECT_EQ(stalled_clients, 1);
  std::printf("batches received by the 19 readers: %llu .. %llu; events broadcast %.0f\n",
              static_cast<unsigned long long>(*std::min_element(batches.begin(), batches.end())),
              static_cast<unsigned long long>(*std::max_element(batches.begin(), batches.end())),
              field(st, "events_broadcast").number_value());
  for (const auto& s : field(st, "streams").list_value().values()) {
    if (field(s, "dropped").number_value() > 0) {
      std::printf("stalled client: dropped %.0f, sent %.0f\n", field(s, "dropped").number_value(),
                  field(s, "sent").number_value());
    }
  }
  EXPECT_EQ(field(st, "streams").list_value().values_size(), kClients);
}

TEST(DashboardStream, AClientThatAcceptsNothingIsDisconnectedAfterTheStallTimeout) {
  smc::dashboard::Options o;
  o.stream_queue_events = 16;
  o.stream_send_buffer = 4096;
  o.stall_timeout = 500ms;
  DashboardFixture f(true, o);
  ASSERT_TRUE(f.make_mill("mill-s"));
  SseClient stalled(f.port(), "/api/stream?raw=1", 4096);
  ASSERT_TRUE(eventually([&] { return stream_count(f.port()) == 1; }));
  uint64_t k = 0;
  ASSERT_TRUE(eventually([&] {
    for (int i = 0; i < 50; ++i) publish_batch(f.cell(), "mill-s", ++k);
    return field(stats(f.port()), "streams_closed_stalled").number_value() >= 1;
  }));
  EXPECT_EQ(stream_count(f.port()), 0u);
}

TEST(DashboardStream, ADepartedClientFreesItsSlot) {
  DashboardFixture f;
  {
    SseClient c(f.port(), "/api/stream");
    ASSERT_TRUE(c.next_named("hello", std::chrono::steady_clock::now() + 5s));
    ASSERT_EQ(stream_count(f.port()), 1u);
  }
  EXPECT_TRUE(eventually([&] { return stream_count(f.port()) == 0; }));
}
