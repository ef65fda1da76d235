/// server_stream: bytes per second per viewer of the version-2 stream (docs/benchmarks.md,
/// "Streaming"), 10 s per case, against a tumble-server child process on 127.0.0.1:
///   server_stream [--server PATH] [--seconds S]
/// Cases: `pile` while it lands (from a reset, all awake), `pile` once every body sleeps,
/// `seed`, `many`. Per case: messages and bytes per second (payload, and on the wire with
/// the WebSocket header; TCP/IP headers left out), what version 1 would have sent (its frame
/// was a fixed 32 + 97 N bytes every 20 ms), and what permessage-deflate would make of the
/// same frames (zlib with the server's settings, run here on the frames received: bytes and
/// CPU µs per frame). Every frame is decoded and applied; a frame that does not apply fails
/// the run. Exits 1 when a budget of issue 13 is missed.
#include <zlib.h>

#include <chrono>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>

#include "child_process.hpp"
#include "frame.hpp"
#include "metrics.hpp"
#include "test_client.hpp"

using namespace tumble::server;
using namespace tumble::server::test;
using Clock = std::chrono::steady_clock;

namespace {

/// Deflate with context takeover, as a permessage-deflate sender (RFC 7692 §7.2.1).
class Deflater {
 public:
  Deflater() { deflateInit2(&z_, 6, Z_DEFLATED, -12, 4, Z_DEFAULT_STRATEGY); }
  ~Deflater() { deflateEnd(&z_); }
  /// Compressed size of `data`, bytes.
  std::size_t compress(const std::string& data) {
    out_.resize(deflateBound(&z_, data.size()) + 64);
    z_.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data()));
    z_.avail_in = static_cast<uInt>(data.size());
    z_.next_out = reinterpret_cast<Bytef*>(out_.data());
    z_.avail_out = static_cast<uInt>(out_.size());
    deflate(&z_, Z_SYNC_FLUSH);
    return out_.size() - z_.avail_out - 4;  // The 00 00 ff ff tail is not sent.
  }

 private:
  z_stream z_{};
  std::string out_;
};

std::size_t ws_header(std::size_t payload) { return payload < 126 ? 2 : payload < 65536 ? 4 : 10; }

struct CaseResult {
  std::string name;
  double seconds = 0;
  std::uint64_t messages = 0, frames = 0, keyframes = 0, wire = 0, payload = 0;
  std::uint64_t deflated = 0;
  double deflate_cpu = 0;
  std::size_t bodies = 0;
  bool ok = true;
};

// Reads for `seconds`, decoding and applying every frame.
CaseResult measure(WsClient& c, FrameDecoder& decoder, const std::string& name, double seconds) {
  CaseResult r;
  r.name = name;
  Deflater deflater;
  const auto start = Clock::now();
  const auto end = start + std::chrono::duration_cast<Clock::duration>(
                               std::chrono::duration<double>(seconds));
  while (Clock::now() < end) {
    const auto m = c.read(std::chrono::milliseconds(2000));
    if (!m) {
      std::cerr << name << ": " << c.last_error().message() << "\n";
      r.ok = false;
      break;
    }
    ++r.messages;
    r.payload += m->data.size();
    r.wire += m->data.size() + ws_header(m->data.size());
    if (m->text) continue;
    const double cpu0 = thread_cpu_seconds();
    r.deflated += deflater.compress(m->data);
    r.deflate_cpu += thread_cpu_seconds() - cpu0;
    const auto f = decode_frame(m->data);
    if (!f || !decoder.apply(*f)) r.ok = false;
    ++r.frames;
    if (f && f->keyframe()) ++r.keyframes;
    if (f) r.bodies = f->body_count;
  }
  r.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return r;
}

// Reads (applying frames) until a status message says every body sleeps, at most `limit`.
bool wait_all_asleep(WsClient& c, FrameDecoder& decoder, std::chrono::seconds limit) {
  for (const auto until = Clock::now() + limit; Clock::now() < until;) {
    const auto m = c.read(std::chrono::milliseconds(2000));
    if (!m) {
      std::cerr << "wait: " << c.last_error().message() << "\n";
      return false;
    }
    if (!m->text) {
      const auto f = decode_frame(m->data);
      if (f) decoder.apply(*f);
      continue;
    }
    const auto j = nlohmann::json::parse(m->data, nullptr, false);
    if (j.value("type", "") == "status" && j.value("bodies", 0) > 0 &&
        j.value("asleep", 0) == j.value("bodies", -1))
      return true;
  }
  return false;
}

void skip(WsClient& c, FrameDecoder& decoder, std::chrono::milliseconds d) {
  for (const auto until = Clock::now() + d; Clock::now() < until;)
    if (const auto m = c.read(std::chrono::milliseconds(2000)); m && !m->text)
      if (const auto f = decode_frame(m->data)) decoder.apply(*f);
}

std::string fixed(double v, int prec) {
  std::ostringstream o;
  o.setf(std::ios::fixed);
  o.precision(prec);
  o << v;
  return o.str();
}

}  // namespace

int main(int argc, char** argv) {
  std::string server = TUMBLE_SERVER_BINARY;
  double seconds = 10.0;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--server") server = argv[i + 1];
    else if (a == "--seconds") seconds = std::stod(argv[i + 1]);
    else return std::cerr << "unknown option " << a << "\n", 2;
  }
  ChildProcess child({server, "--port", "0", "--scene", "pile", "--render-ms", "20"},
                     /*merge_stderr=*/false);
  const std::string url = child.line();
  if (url.find("http://") == std::string::npos) return std::cerr << "no server: " << url, 1;
  const auto port = static_cast<std::uint16_t>(std::stoi(url.substr(url.rfind(':') + 1)));

  WsClient c(port);
  FrameDecoder decoder;
  std::vector<CaseResult> results;
  http_post(port, "/api/reset", R"({"scene": "pile"})");
  results.push_back(measure(c, decoder, "pile, landing (from a reset)", seconds));
  const bool slept = wait_all_asleep(c, decoder, std::chrono::seconds(90));
  skip(c, decoder, std::chrono::milliseconds(600));  // The status after the last change.
  results.push_back(measure(c, decoder, slept ? "pile, all asleep" : "pile, NOT all asleep", seconds));
  for (const char* scene : {"seed", "many"}) {
    http_post(port, "/api/reset", std::string(R"({"scene": ")") + scene + "\"}");
    skip(c, decoder, std::chrono::seconds(1));
    results.push_back(measure(c, decoder, scene, seconds));
  }
  const std::string metrics = http_get(port, "/metrics").body;
  child.stop();

  // Budgets of issue 13, bytes/s on the wire per viewer.
  const auto budget = [&](const CaseResult& r) -> std::pair<double, std::string> {
    const double v1 = 50.0 * (32 + 97.0 * r.bodies + ws_header(32 + 97 * r.bodies));
    if (r.name.starts_with("pile, landing")) return {1.5e6, "<= 1.5 MB/s"};
    if (r.name.starts_with("pile")) return {2e3, "<= 2 KB/s"};
    if (r.name == "seed") return {4e3, "<= 4 KB/s"};
    return {v1 / 4, "<= v1 / 4"};
  };
  std::cout << "server_stream: one viewer, " << seconds << " s per case, 20 ms frames\n\n"
            << "| case | bodies | messages/s | keyframes | wire bytes/s | bytes/body-frame | v1 bytes/s "
               "| v2 / v1 | deflated bytes/s | deflate µs/frame | budget | |\n"
            << "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  bool all = true;
  for (const CaseResult& r : results) {
    const double wire = r.wire / r.seconds;
    const double v1 = 50.0 * (32 + 97.0 * r.bodies + ws_header(32 + 97 * r.bodies));
    const auto [limit, text] = budget(r);
    const bool pass = r.ok && wire <= limit && !r.name.ends_with("NOT all asleep");
    all = all && pass;
    const double body_frames = r.frames ? static_cast<double>(r.frames) * r.bodies : 1.0;
    std::cout << "| " << r.name << " | " << r.bodies << " | " << fixed(r.messages / r.seconds, 1)
              << " | " << r.keyframes << " | " << fixed(wire, 0) << " | "
              << fixed(r.payload / body_frames, 2) << " | " << fixed(v1, 0) << " | "
              << fixed(wire / v1, 5) << " | " << fixed(r.deflated / r.seconds, 0) << " | "
              << fixed(r.frames ? 1e6 * r.deflate_cpu / r.frames : 0, 1) << " | " << text
              << " | " << (pass ? "ok" : "FAIL") << (r.ok ? "" : " (undecodable)") << " |\n";
  }
  std::cout << "\nbytes/body-frame: payload bytes over (frames × bodies in the scene)\n"
            << "\n" << (all ? "PASS" : "FAIL") << "\n";
  return all ? 0 : 1;
}
