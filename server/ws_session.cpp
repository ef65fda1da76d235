#include "ws_session.hpp"

#include <boost/asio/dispatch.hpp>
#include <boost/asio/post.hpp>

#include <random>

#include "broadcaster.hpp"
#include "log.hpp"

namespace tumble::server {

namespace beast = boost::beast;
namespace websocket = beast::websocket;
namespace net = boost::asio;

WsSession::WsSession(net::ip::tcp::socket&& socket, Broadcaster& broadcaster, Metrics& metrics,
                     std::chrono::milliseconds timeout, ConnectionCount::Slot slot)
    : ws_(std::move(socket)),
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
  read_buffer_.consume(read_buffer_.size());  // Client messages are ignored.
  do_read();
}

void WsSession::deliver(std::shared_ptr<const std::string> frame,
                        std::shared_ptr<const SceneInfo> scene) {
  net::post(ws_.get_executor(),
            beast::bind_front_handler(&WsSession::on_deliver, shared_from_this(),
                                      std::move(frame), std::move(scene)));
}

void WsSession::on_deliver(std::shared_ptr<const std::string> frame,
                           std::shared_ptr<const SceneInfo> scene) {
  if (!accepted_ || closing_ || finished_) return;
  if (scene->generation < generation_) return;  // A frame of a scene already replaced.
  if (scene->generation > generation_) {
    generation_ = scene->generation;
    pending_scene_ = scene->message;
    if (pending_frame_) metrics_.count_frame_dropped();
    pending_frame_.reset();
  }
  if (pending_frame_) metrics_.count_frame_dropped();  // Newest wins.
  pending_frame_ = std::move(frame);
  if (!writing_) do_write();
}

void WsSession::do_write() {
  bool is_frame = false;
  if (pending_scene_) {
    in_flight_ = std::exchange(pending_scene_, nullptr);
    ws_.text(true);
  } else if (pending_frame_) {
    in_flight_ = std::exchange(pending_frame_, nullptr);
    ws_.binary(true);
    is_frame = true;
  } else {
    return;
  }
  writing_ = true;
  ws_.async_write(net::buffer(*in_flight_),
                  beast::bind_front_handler(&WsSession::on_write, shared_from_this(), is_frame));
}

void WsSession::on_write(bool is_frame, beast::error_code ec, std::size_t) {
  writing_ = false;
  in_flight_.reset();
  if (ec) {
    fail(ec, "websocket write");
    return finish();
  }
  if (is_frame) metrics_.count_frame_sent();
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
  ping_timer_.cancel();
  pending_frame_.reset();
  pending_scene_.reset();
  broadcaster_.leave(this);
}

}  // namespace tumble::server
