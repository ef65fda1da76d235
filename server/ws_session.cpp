#include "ws_session.hpp"

#include <boost/asio/dispatch.hpp>
#include <boost/asio/post.hpp>

#include "broadcaster.hpp"
#include "log.hpp"

namespace tumble::server {

namespace beast = boost::beast;
namespace websocket = beast::websocket;
namespace net = boost::asio;

WsSession::WsSession(net::ip::tcp::socket&& socket, Broadcaster& broadcaster, Metrics& metrics)
    : ws_(std::move(socket)), broadcaster_(broadcaster), metrics_(metrics) {}

void WsSession::run(beast::http::request<beast::http::string_body> request) {
  // The websocket stream's own timeouts replace the tcp_stream's.
  beast::get_lowest_layer(ws_).expires_never();
  websocket::stream_base::timeout timeout =
      websocket::stream_base::timeout::suggested(beast::role_type::server);
  timeout.idle_timeout = std::chrono::seconds(30);
  timeout.keep_alive_pings = true;
  ws_.set_option(timeout);
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
  pending_frame_.reset();
  pending_scene_.reset();
  broadcaster_.leave(this);
}

}  // namespace tumble::server
