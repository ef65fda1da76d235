#include "ws_session.hpp"

#include <boost/asio/dispatch.hpp>
#include <boost/asio/post.hpp>

#include <algorithm>
#include <random>

#include <nlohmann/json.hpp>

#include "broadcaster.hpp"
#include "log.hpp"

namespace tumble::server {

namespace beast = boost::beast;
namespace websocket = beast::websocket;
namespace net = boost::asio;

WsSession::WsSession(net::ip::tcp::socket&& socket, Broadcaster& broadcaster, Metrics& metrics,
                     std::chrono::milliseconds timeout, ConnectionCount::Slot slot,
                     std::shared_ptr<const void> owner)
    : ws_(std::move(socket)),
      owner_(std::move(owner)),
      broadcaster_(broadcaster),
      metrics_(metrics),
      ping_timer_(ws_.get_executor()),
      timeout_(timeout),
      slot_(std::move(slot)) {}

void WsSession::run(beast::http::request<beast::http::string_body> request) {
  // The websocket stream's own timeouts replace the tcp_stream's.
  beast::get_lowest_layer(ws_).expires_never();
  websocket::stream_base::timeout timeout =
      websocket::stream_base::timeout::suggested(beast::role_type::server);
  // Our own pings (do_ping_timer) replace Beast's idle timeout: a peer that sends nothing at
  // all sends no pong either. (Beast's idle timeout without its keep-alive pings is a hard
  // deadline from the upgrade on, not an idle one.)
  timeout.idle_timeout = websocket::stream_base::none();
  timeout.keep_alive_pings = false;
  ws_.set_option(timeout);
  ws_.control_callback([this](websocket::frame_type kind, beast::string_view payload) {
    if (kind == websocket::frame_type::pong && ping_outstanding_ &&
        payload == beast::string_view(ping_payload_.data(), ping_payload_.size())) {
      ping_outstanding_ = false;
      ticks_unanswered_ = 0;
    }
  });
  ws_.set_option(websocket::stream_base::decorator([](websocket::response_type& res) {
    res.set(beast::http::field::server, "tumble-server");
  }));
  ws_.read_message_max(kMaxClientMessage);
  // permessage-deflate when the client offers it; used for text messages and keyframes only
  // (WsSession::write_frame): deltas are compressed per viewer, which costs more CPU than
  // the bytes it saves (docs/benchmarks.md).
  websocket::permessage_deflate deflate;
  deflate.server_enable = true;
  deflate.server_max_window_bits = 12;
  deflate.memLevel = 4;
  deflate.compLevel = 6;
  ws_.set_option(deflate);
  // One WebSocket frame per message: a 25 kB frame in Beast's default 4 kB fragments costs
  // seven writes per viewer instead of one.
  ws_.auto_fragment(false);
  ws_.async_accept(request, beast::bind_front_handler(&WsSession::on_accept, shared_from_this()));
}

void WsSession::on_accept(beast::error_code ec) {
  if (ec) {
    fail(ec, "websocket accept");
    return finish();
  }
  accepted_ = true;
  if (closing_) return do_close();
  if (!broadcaster_.join(shared_from_this())) {
    closing_ = true;
    close_sent_ = true;
    ws_.async_close(websocket::close_reason(websocket::close_code::try_again_later, "too many viewers"),
                    [self = shared_from_this()](beast::error_code) { self->finish(); });
    return;
  }
  const std::shared_ptr<const SceneInfo> scene = broadcaster_.current_scene();
  generation_ = scene->generation;
  pending_scene_ = scene->message;
  frame_waiting_ = true;  // The newest frame, if any, right after the scene message.
  do_write();
  do_read();
  do_ping_timer();
}

void WsSession::do_ping_timer() {
  ping_timer_.expires_after(timeout_ / 2);
  ping_timer_.async_wait(beast::bind_front_handler(&WsSession::on_ping_timer, shared_from_this()));
}

// A viewer must show it reads: a ping with a random payload goes out behind the frames
// already queued, and only a client that read up to it can echo the payload (an unsolicited
// pong sent blind does not match). Unanswered for two ticks (the timeout): dropped.
void WsSession::on_ping_timer(beast::error_code ec) {
  if (ec || finished_ || closing_) return;
  if (ping_outstanding_) {
    if (++ticks_unanswered_ >= 2) return drop();
    return do_ping_timer();
  }
  static thread_local std::mt19937_64 random{std::random_device{}()};
  const std::string nonce = std::to_string(random());
  ping_payload_.assign(nonce.data(), nonce.size());
  ping_outstanding_ = true;
  ticks_unanswered_ = 0;
  ws_.async_ping(ping_payload_, [self = shared_from_this()](beast::error_code ec) {
    if (ec) self->finish();
  });
  do_ping_timer();
}

// No close frame: a peer that does not read would never take it.
void WsSession::drop() {
  beast::error_code ec;
  beast::get_lowest_layer(ws_).socket().close(ec);
  finish();
}

void WsSession::do_read() {
  ws_.async_read(read_buffer_, beast::bind_front_handler(&WsSession::on_read, shared_from_this()));
}

void WsSession::on_read(beast::error_code ec, std::size_t) {
  if (ec) {  // Closed by the client or by us, too big, timed out: the end of the session.
    fail(ec, "websocket read");
    return finish();
  }
  if (ws_.got_text()) on_client_message();
  read_buffer_.consume(read_buffer_.size());
  do_read();
}

// The client messages understood: {"type": "ack", "frame": n[, "window": w]} and
// {"type": "contacts", "on": bool}. Anything else is ignored.
void WsSession::on_client_message() {
  const auto data = read_buffer_.cdata();
  const nlohmann::json j = nlohmann::json::parse(
      static_cast<const char*>(data.data()), static_cast<const char*>(data.data()) + data.size(),
      nullptr, /*allow_exceptions=*/false);
  if (j.is_object() && j.size() == 2 && j.value("type", "") == "contacts" && j.contains("on") &&
      j["on"].is_boolean()) {
    const bool on = j["on"].get<bool>();
    if (on != contacts_on_ && !finished_) {
      contacts_on_ = on;
      broadcaster_.subscribe_contacts(on ? 1 : -1);
      contacts_step_sent_.reset();
      contacts_due_ = on;
    }
    return;
  }
  if (!j.is_object() || j.value("type", "") != "ack" || !j.contains("frame") ||
      !j["frame"].is_number_unsigned())
    return;
  const auto frame = j["frame"].get<std::uint64_t>();
  if (j.contains("window") && j["window"].is_number_unsigned())
    ack_window_ = std::clamp<std::size_t>(j["window"].get<std::size_t>(), 1, kAckWindow);
  acking_ = true;
  while (!unacked_.empty() && unacked_.front() <= frame) unacked_.pop_front();
  if (!writing_) do_write();
}

void WsSession::notify() {
  net::post(ws_.get_executor(),
            beast::bind_front_handler(&WsSession::on_notify, shared_from_this()));
}

void WsSession::on_notify() {
  if (!accepted_ || closing_ || finished_) return;
  if (busy() && frame_waiting_ && base_) {  // The frame announced before is never sent.
    ++dropped_;
    metrics_.count_frame_dropped();
  }
  frame_waiting_ = true;
  if (!writing_) do_write();
}

bool WsSession::busy() const {
  return writing_ || (acking_ && unacked_.size() >= ack_window_);
}

// Order: the first scene message, a newer scene's message (it resets the delta base), a new
// status, then the newest frame. One write at a time; on_write comes back here.
void WsSession::do_write() {
  if (writing_ || closing_ || finished_) return;
  if (pending_scene_) return write_text(std::exchange(pending_scene_, nullptr));
  const Published pub = broadcaster_.store().newest();
  if (!pub.state || pub.state->generation < generation_) return;
  if (pub.state->generation > generation_) {
    generation_ = pub.state->generation;
    base_.reset();
    return write_text(pub.scene->message);
  }
  if (contacts_on_ && contacts_due_ && pub.contacts && pub.contacts_step != contacts_step_sent_) {
    contacts_due_ = false;
    contacts_step_sent_ = pub.contacts_step;
    return write_text(pub.contacts);
  }
  if (pub.status && pub.status_sequence != status_sent_) {
    status_sent_ = pub.status_sequence;
    nlohmann::json status = *pub.status;
    status["dropped"] = dropped_;
    return write_text(std::make_shared<const std::string>(status.dump()));
  }
  if (frame_waiting_ && !busy() && write_frame(pub.state)) return;
}

// Sends `state` against base_ unless it would tell the viewer nothing new: nothing changed
// since base_ (same flags, no body changed after it) and the last frame is recent.
bool WsSession::write_frame(const std::shared_ptr<const FrameState>& state) {
  frame_waiting_ = false;
  const auto now = std::chrono::steady_clock::now();
  if (base_) {
    if (base_->number == state->number) return false;
    const bool unchanged = state->last_change <= base_->number && state->flags == base_->flags;
    if (unchanged && now - last_frame_at_ < std::chrono::milliseconds(kHeartbeatMs)) return false;
  }
  const double cpu0 = thread_cpu_seconds();
  in_flight_ = broadcaster_.store().encoded(state, base_.get());
  metrics_.add_stream_cpu(thread_cpu_seconds() - cpu0);
  ws_.compress(!base_);  // Keyframes only: see docs/benchmarks.md, "permessage-deflate".
  base_ = state;
  last_frame_at_ = now;
  if (acking_) unacked_.push_back(state->number);
  writing_ = true;
  metrics_.add_frames_in_flight(1);
  ws_.binary(true);
  ws_.async_write(net::buffer(*in_flight_),
                  beast::bind_front_handler(&WsSession::on_write, shared_from_this(), true));
  return true;
}

void WsSession::write_text(std::shared_ptr<const std::string> text) {
  in_flight_ = std::move(text);
  writing_ = true;
  ws_.compress(true);
  ws_.text(true);
  ws_.async_write(net::buffer(*in_flight_),
                  beast::bind_front_handler(&WsSession::on_write, shared_from_this(), false));
}

void WsSession::on_write(bool is_frame, beast::error_code ec, std::size_t) {
  writing_ = false;
  if (is_frame) {
    metrics_.add_frames_in_flight(-1);
    metrics_.count_frame_sent();
    metrics_.add_frame_bytes(in_flight_->size());
    contacts_due_ = contacts_on_;
  }
  in_flight_.reset();
  if (ec) {
    fail(ec, "websocket write");
    return finish();
  }
  if (closing_) return do_close();
  do_write();
}

void WsSession::close() {
  net::post(ws_.get_executor(), [self = shared_from_this()] {
    self->closing_ = true;
    if (self->accepted_ && !self->writing_) self->do_close();
  });
}

void WsSession::do_close() {
  if (close_sent_ || finished_) return;
  close_sent_ = true;
  ws_.async_close(websocket::close_code::going_away,
                  [self = shared_from_this()](beast::error_code) {});
}

void WsSession::finish() {
  if (finished_) return;
  finished_ = true;
  if (std::exchange(contacts_on_, false)) broadcaster_.subscribe_contacts(-1);
  ping_timer_.cancel();
  pending_scene_.reset();
  base_.reset();
  broadcaster_.leave(this);
}

}  // namespace tumble::server
