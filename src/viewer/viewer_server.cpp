#include "viewer/viewer_server.h"

#include <utility>   // Boost 1.74's asio/awaitable.hpp uses std::exchange without including it (C++20)

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include <pthread.h>
#include <signal.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <iostream>
#include <mutex>
#include <optional>
#include <thread>

#include "core/types.h"
#include "viewer/assets.h"

namespace vkmesh::viewer {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
using Message = std::shared_ptr<const std::string>;

class WsSession;

enum class Mode { Live, Mesh, Stream };

struct Server::Impl {
    // Declared first, destroyed last: the sessions its pending handlers own go before it.
    asio::io_context ioc{1};
    tcp::acceptor acceptor{ioc};
    ServerOptions options;
    std::string host;
    uint16_t port = 0;
    std::thread thread;
    std::atomic<bool> stopped{false};

    // Everything below is touched on the I/O thread only, except `stats` (under statsMutex).
    Mode mode = Mode::Live;   // until setMesh or setStream
    RecordSet mesh{false};                       // Live: the current mesh (what a late page gets first)
    FrameInfo info;                              // Live: the latest frame's
    std::vector<std::array<float, 3>> trajectory;
    Message meshMessage;                         // Mesh: the one message every page gets
    std::vector<MeshDelta> frames;               // Stream: the file's frames
    std::vector<std::weak_ptr<WsSession>> sessions;
    std::vector<std::weak_ptr<beast::tcp_stream>> httpStreams;   // closed by stop()
    std::function<void(const std::vector<std::pair<std::string, double>>&)> reportCallback;

    mutable std::mutex statsMutex;
    ServerStats stats;

    void accept();
    void onFrame(const std::shared_ptr<const MeshDelta>& delta, const FrameInfo& frameInfo);
    void countSent(size_t bytes) {
        std::lock_guard lock(statsMutex);
        ++stats.messagesSent;
        stats.bytesSent += bytes;
    }
    void log(const std::string& line) const {
        if (!options.quiet) std::cerr << "vkmesh viewer: " << line << "\n";
    }
};

// One page's WebSocket: at most one message in flight; what comes meanwhile waits in `next` (a reset, which
// supersedes everything before it) and `pending` (live frames merged, last record per id wins).
class WsSession : public std::enable_shared_from_this<WsSession> {
public:
    WsSession(tcp::socket socket, Server::Impl& server) : ws_(std::move(socket)), server_(server), timer_(server.ioc) {}

    void run(http::request<http::string_body> request) {
        ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
        ws_.read_message_max(4096);   // a page sends short commands only
        ws_.binary(true);
        ws_.async_accept(request, [self = shared_from_this()](beast::error_code ec) { self->onAccept(ec); });
    }

    void onFrame(const Message& encoded, const MeshDelta& delta, const FrameInfo& info) {
        if (!open_) return;   // it gets the mesh with this frame in it when it opens
        if (!writing_ && !next_ && pendingFrames_ == 0) {
            write(encoded);
            return;
        }
        pending_.apply(delta);
        pendingInfo_ = info;
        if (info.hasCamera) pendingTrajectory_.push_back({info.cameraToWorld[3], info.cameraToWorld[7], info.cameraToWorld[11]});
        ++pendingFrames_;
        std::lock_guard lock(server_.statsMutex);
        ++server_.stats.framesCoalesced;
    }

    void close() {
        beast::error_code ec;
        timer_.cancel();
        beast::get_lowest_layer(ws_).socket().shutdown(tcp::socket::shutdown_both, ec);
        beast::get_lowest_layer(ws_).socket().close(ec);
    }

private:
    void onAccept(beast::error_code ec) {
        if (ec) return;
        open_ = true;
        server_.sessions.push_back(weak_from_this());
        {
            std::lock_guard lock(server_.statsMutex);
            ++server_.stats.pagesConnected;
            ++server_.stats.pagesOpen;
        }
        server_.log("page connected (" + std::to_string(server_.sessions.size()) + " open)");
        switch (server_.mode) {
        case Mode::Live:
            write(std::make_shared<const std::string>(
                encodeRecordSet(server_.mesh, kWireReset, server_.info, server_.info.frame, server_.trajectory)));
            break;
        case Mode::Mesh:
            if (server_.meshMessage) write(server_.meshMessage);
            break;
        case Mode::Stream:
            seek(0);
            tick();
            break;
        }
        read();
    }

    void read() {
        ws_.async_read(buffer_, [self = shared_from_this()](beast::error_code ec, size_t) { self->onRead(ec); });
    }

    void onRead(beast::error_code ec) {
        if (ec) return finish();   // closed by the page, reset, or a message over read_message_max (Beast closes it)
        ClientCommand command;
        const std::string text = beast::buffers_to_string(buffer_.data());
        buffer_.consume(buffer_.size());
        if (!ws_.got_text() || !parseClientCommand(text, command)) return malformed();
        switch (command.kind) {
        case ClientCommand::Kind::Ack: {
            std::lock_guard lock(server_.statsMutex);
            server_.stats.lastAck = command.value;
            server_.stats.lagAtAck.push_back(server_.stats.lastFrame > command.value ? server_.stats.lastFrame - command.value : 0);
            break;
        }
        case ClientCommand::Kind::Seek:
            if (server_.mode == Mode::Stream) seek(std::min<size_t>(command.value, server_.frames.size()));
            break;
        case ClientCommand::Kind::Play:
            if (server_.mode == Mode::Stream && !playing_) {
                playing_ = true;
                if (cursor_ >= server_.frames.size()) seek(0);   // play again from the start
                tick();
            }
            break;
        case ClientCommand::Kind::Pause:
            playing_ = false;
            break;
        case ClientCommand::Kind::Report:
            {
                std::lock_guard lock(server_.statsMutex);
                server_.stats.reports.push_back(command.report);
            }
            if (server_.reportCallback) server_.reportCallback(command.report);
            break;
        }
        read();
    }

    // A message that is not one of the page's commands: this connection only is closed (policy violation).
    void malformed() {
        {
            std::lock_guard lock(server_.statsMutex);
            ++server_.stats.pagesClosedMalformed;
        }
        server_.log("closing a page's connection: malformed message");
        if (writing_) {
            close();   // a close frame cannot be sent while a write is in flight
        } else {
            ws_.async_close(websocket::close_code::policy_error, [self = shared_from_this()](beast::error_code) { self->close(); });
        }
        finish();
    }

    void finish() {
        if (!open_) return;
        open_ = false;
        timer_.cancel();
        std::lock_guard lock(server_.statsMutex);
        --server_.stats.pagesOpen;
        server_.log("page disconnected");
    }

    void write(const Message& message) {
        writing_ = true;
        ws_.async_write(asio::buffer(*message), [self = shared_from_this(), message](beast::error_code ec, size_t bytes) {
            self->writing_ = false;
            if (ec) {
                self->close();
                return self->finish();
            }
            self->server_.countSent(bytes);
            self->afterWrite();
        });
    }

    void afterWrite() {
        if (!open_) return;
        if (next_) {
            Message m = std::move(next_);
            next_.reset();
            return write(m);
        }
        if (pendingFrames_ > 0) {
            Message m = std::make_shared<const std::string>(
                encodeRecordSet(pending_, 0, pendingInfo_, pendingFrames_, pendingTrajectory_));
            pending_.clear();
            pendingTrajectory_.clear();
            pendingFrames_ = 0;
            return write(m);
        }
    }

    // Stream files: the mesh after `frame` frames as a reset, then frames from there on at the play pace.
    void seek(size_t frame) {
        RecordSet state(false);
        for (size_t i = 0; i < frame; ++i) state.apply(server_.frames[i]);
        FrameInfo info;
        info.frame = uint32_t(frame);
        info.totalFrames = uint32_t(server_.frames.size());
        info.source = kSourceStream;
        next_ = std::make_shared<const std::string>(encodeRecordSet(state, kWireReset, info, uint32_t(frame), {}));
        pending_.clear();
        pendingFrames_ = 0;
        cursor_ = frame;
        if (!writing_) afterWrite();
    }

    void tick() {
        if (!open_ || !playing_) return;
        if (!writing_ && !next_ && cursor_ < server_.frames.size()) {
            FrameInfo info;
            info.frame = uint32_t(cursor_ + 1);
            info.totalFrames = uint32_t(server_.frames.size());
            info.source = kSourceStream;
            write(std::make_shared<const std::string>(encodeDelta(server_.frames[cursor_], info, {})));
            ++cursor_;
        }
        if (cursor_ >= server_.frames.size()) {
            playing_ = false;
            return;
        }
        timer_.expires_after(std::chrono::microseconds(int64_t(1e6 / std::max(0.1, server_.options.playFps))));
        timer_.async_wait([self = shared_from_this()](beast::error_code ec) {
            if (!ec) self->tick();
        });
    }

    websocket::stream<beast::tcp_stream> ws_;
    Server::Impl& server_;
    beast::flat_buffer buffer_;
    asio::steady_timer timer_;
    bool open_ = false, writing_ = false, playing_ = true;
    Message next_;
    RecordSet pending_{true};
    FrameInfo pendingInfo_;
    uint32_t pendingFrames_ = 0;
    std::vector<std::array<float, 3>> pendingTrajectory_;
    size_t cursor_ = 0;
};

// One HTTP connection: the page's assets, or the upgrade to the page's WebSocket at /ws. Any other path: 404.
class HttpSession : public std::enable_shared_from_this<HttpSession> {
public:
    HttpSession(tcp::socket socket, Server::Impl& server)
        : stream_(std::make_shared<beast::tcp_stream>(std::move(socket))), server_(server) {}

    void run() {
        std::erase_if(server_.httpStreams, [](const auto& w) { return w.expired(); });
        server_.httpStreams.push_back(stream_);
        read();
    }

private:
    void read() {
        parser_.emplace();
        parser_->body_limit(4096);
        parser_->header_limit(8192);
        stream_->expires_after(std::chrono::seconds(60));
        http::async_read(*stream_, buffer_, *parser_, [self = shared_from_this()](beast::error_code ec, size_t) { self->onRead(ec); });
    }

    void onRead(beast::error_code ec) {
        if (ec == http::error::end_of_stream) {
            stream_->socket().shutdown(tcp::socket::shutdown_send, ec);
            return;
        }
        if (ec) return;   // a request Beast cannot parse (or a timeout): the connection is dropped
        http::request<http::string_body> request = parser_->release();
        const std::string target(request.target());
        if (websocket::is_upgrade(request) && target == "/ws") {
            stream_->expires_never();
            std::make_shared<WsSession>(stream_->release_socket(), server_)->run(std::move(request));
            return;
        }
        auto response = std::make_shared<http::response<http::string_body>>();
        response->version(request.version());
        response->keep_alive(request.keep_alive());
        response->set(http::field::server, "vkmesh");
        response->set(http::field::cache_control, "no-store");
        response->set("X-Content-Type-Options", "nosniff");
        // Only the exact paths of the embedded assets; a query string (cache busting) is ignored. Nothing is
        // ever looked up on disk, so "..", encoded or not, can only miss the table.
        const std::string path = target.substr(0, target.find('?'));
        const Asset* asset = findAsset(path);
        if (request.method() != http::verb::get && request.method() != http::verb::head) {
            response->result(http::status::method_not_allowed);
            response->set(http::field::allow, "GET, HEAD");
        } else if (!asset) {
            response->result(http::status::not_found);
            response->set(http::field::content_type, "text/plain");
            response->body() = "404 not found\n";
        } else {
            response->result(http::status::ok);
            response->set(http::field::content_type, std::string(asset->contentType));
            if (request.method() == http::verb::get) response->body().assign(asset->body);
            else response->content_length(asset->body.size());
        }
        if (request.method() == http::verb::head && asset) {
            http::response<http::empty_body> head{response->result(), response->version()};
            for (const auto& field : *response) head.set(std::string(field.name_string()), std::string(field.value()));
            head.content_length(asset->body.size());
            head.keep_alive(response->keep_alive());
            auto h = std::make_shared<http::response<http::empty_body>>(std::move(head));
            http::async_write(*stream_, *h, [self = shared_from_this(), h](beast::error_code e, size_t) { self->onWrite(e, h->keep_alive()); });
            return;
        }
        response->prepare_payload();
        http::async_write(*stream_, *response,
                          [self = shared_from_this(), response](beast::error_code e, size_t) { self->onWrite(e, response->keep_alive()); });
    }

    void onWrite(beast::error_code ec, bool keepAlive) {
        if (ec) return;
        if (!keepAlive) {
            stream_->socket().shutdown(tcp::socket::shutdown_send, ec);
            return;
        }
        read();
    }

    std::shared_ptr<beast::tcp_stream> stream_;
    Server::Impl& server_;
    beast::flat_buffer buffer_;
    std::optional<http::request_parser<http::string_body>> parser_;
};

void Server::Impl::accept() {
    acceptor.async_accept(ioc, [this](beast::error_code ec, tcp::socket socket) {
        if (ec) {
            if (ec == asio::error::operation_aborted || stopped) return;
            log(std::string("accept failed: ") + ec.message());
        } else {
            socket.set_option(tcp::no_delay(true), ec);
            std::make_shared<HttpSession>(std::move(socket), *this)->run();
        }
        accept();
    });
}

void Server::Impl::onFrame(const std::shared_ptr<const MeshDelta>& delta, const FrameInfo& frameInfo) {
    mesh.apply(*delta);
    info = frameInfo;
    info.source = kSourceLive;
    std::vector<std::array<float, 3>> point;
    if (frameInfo.hasCamera) {
        point.push_back({frameInfo.cameraToWorld[3], frameInfo.cameraToWorld[7], frameInfo.cameraToWorld[11]});
        trajectory.push_back(point.back());
    }
    {
        std::lock_guard lock(statsMutex);
        ++stats.framesPublished;
        stats.lastFrame = frameInfo.frame;
    }
    // Encoded once for every page that is keeping up; a page that is not merges the delta instead.
    Message encoded;
    std::erase_if(sessions, [](const std::weak_ptr<WsSession>& s) { return s.expired(); });
    for (auto& weak : sessions)
        if (auto s = weak.lock()) {
            if (!encoded) encoded = std::make_shared<const std::string>(encodeDelta(*delta, info, point));
            s->onFrame(encoded, *delta, info);
        }
}

Server::Server(const ServerOptions& options) : impl_(std::make_shared<Impl>()) {
    Impl& s = *impl_;
    s.options = options;
    s.host = options.host == "localhost" ? "127.0.0.1" : options.host;
    beast::error_code ec;
    const asio::ip::address address = asio::ip::make_address(s.host, ec);
    if (ec) throw Error("--host '" + options.host + "' is not an IP address (e.g. 127.0.0.1, 0.0.0.0, ::1)");
    const tcp::endpoint endpoint(address, options.port);
    s.acceptor.open(endpoint.protocol(), ec);
    if (!ec) s.acceptor.set_option(asio::socket_base::reuse_address(true), ec);
    if (!ec) s.acceptor.bind(endpoint, ec);
    if (ec == asio::error::address_in_use)
        throw Error("port " + std::to_string(options.port) + " on " + s.host + " is in use (choose another with --port)");
    if (ec == asio::error::access_denied)
        throw Error("port " + std::to_string(options.port) + " on " + s.host + " needs privileges (choose one above 1023 with --port)");
    if (ec) throw Error("cannot listen on " + s.host + " port " + std::to_string(options.port) + ": " + ec.message());
    s.acceptor.listen(asio::socket_base::max_listen_connections, ec);
    if (ec) throw Error("cannot listen on " + s.host + " port " + std::to_string(options.port) + ": " + ec.message());
    s.port = s.acceptor.local_endpoint().port();
    s.info.source = kSourceLive;   // until setMesh or setStream: a page joining before the first frame is live too
    s.accept();
    // The I/O thread takes no signals (Ctrl-C must reach the thread that waits for it: the CLI's, or Python's main
    // thread), as Mesa's driver threads do.
    sigset_t all, previous;
    sigfillset(&all);
    pthread_sigmask(SIG_BLOCK, &all, &previous);
    s.thread = std::thread([&s] { s.ioc.run(); });
    pthread_sigmask(SIG_SETMASK, &previous, nullptr);
}

Server::~Server() { stop(); }

std::string Server::url() const {
    const bool v6 = impl_->host.find(':') != std::string::npos;
    return "http://" + (v6 ? "[" + impl_->host + "]" : impl_->host) + ":" + std::to_string(impl_->port) + "/";
}

uint16_t Server::port() const { return impl_->port; }

void Server::setMesh(const Mesh& mesh, const FrameInfo& info) {
    auto message = std::make_shared<const std::string>(encodeMesh(mesh, info));
    asio::post(impl_->ioc, [s = impl_.get(), message] {
        s->mode = Mode::Mesh;
        s->meshMessage = message;
    });
}

void Server::setStream(std::vector<MeshDelta> frames) {
    auto shared = std::make_shared<std::vector<MeshDelta>>(std::move(frames));
    asio::post(impl_->ioc, [s = impl_.get(), shared] {
        s->mode = Mode::Stream;
        s->frames = std::move(*shared);
    });
}

void Server::publish(const MeshDelta& delta, const FrameInfo& info) {
    if (impl_->stopped) return;
    auto copy = std::make_shared<const MeshDelta>(delta);
    asio::post(impl_->ioc, [s = impl_.get(), copy, info] { s->onFrame(copy, info); });
}

ServerStats Server::stats() const {
    std::lock_guard lock(impl_->statsMutex);
    return impl_->stats;
}

void Server::onReport(std::function<void(const std::vector<std::pair<std::string, double>>&)> callback) {
    asio::post(impl_->ioc, [s = impl_.get(), callback = std::move(callback)] { s->reportCallback = callback; });
}

void Server::stop() {
    if (!impl_ || impl_->stopped.exchange(true)) return;
    Impl* s = impl_.get();
    asio::post(s->ioc, [s] {
        beast::error_code ec;
        s->acceptor.close(ec);
        for (auto& weak : s->sessions)
            if (auto session = weak.lock()) session->close();
        for (auto& weak : s->httpStreams)
            if (auto stream = weak.lock()) stream->socket().close(ec);
        s->ioc.stop();
    });
    if (s->thread.joinable()) s->thread.join();
}

void blockStopSignals() {
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &set, nullptr);
}

bool waitForStopSignal(double seconds) {
    blockStopSignals();
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    if (seconds < 0) {
        int sig = 0;
        sigwait(&set, &sig);
        return true;
    }
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    for (;;) {
        const double left = std::chrono::duration<double>(end - std::chrono::steady_clock::now()).count();
        if (left <= 0) return false;
        timespec timeout{time_t(left), long((left - std::floor(left)) * 1e9)};
        if (sigtimedwait(&set, nullptr, &timeout) > 0) return true;
    }
}

bool stopSignalPending() {
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    timespec zero{0, 0};
    return sigtimedwait(&set, nullptr, &zero) > 0;
}

}  // namespace vkmesh::viewer
