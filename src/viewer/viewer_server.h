// The browser viewer's server (docs/VIEWER.md): HTTP for the page's own embedded assets and one WebSocket per
// page that carries the mesh (viewer/wire.h). Boost.Beast on one I/O thread of its own; nothing here is
// called from the GPU library, and no Boost type appears in this header (the CLI and the Python module
// include it without Boost's headers' cost).
//
// Three sources, one per server:
//  - a static mesh (setMesh: `vkmesh view mesh.ply|map.vkmap`): every page gets it as one message;
//  - a delta stream file (setStream: `vkmesh view run.deltas`): every page plays it frame by frame at its own
//    pace, with a slider (seek);
//  - live frames (publish: `vkmesh fuse --serve`, Python `Reconstructor.serve`): a page joining late gets the
//    current mesh, then every frame's delta. A page that cannot keep up has at most one message in flight
//    and one pending: later frames are merged into the pending one (last record per id wins), so memory per
//    page is bounded by the mesh, and publish() never waits for a socket.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/mesh_delta.h"
#include "io/ply.h"
#include "viewer/wire.h"

namespace vkmesh::viewer {

struct ServerOptions {
    std::string host = "127.0.0.1";   // any other address must be asked for (--host)
    uint16_t port = 8080;             // 0: any free port (tests)
    double playFps = 30;              // a stream file's playback pace
    bool quiet = false;               // no line per page connected / disconnected
};

// What the server has done so far (for --stats and the measurements).
struct ServerStats {
    uint64_t pagesConnected = 0, pagesOpen = 0, pagesClosedMalformed = 0;
    uint64_t messagesSent = 0, bytesSent = 0, framesPublished = 0, framesCoalesced = 0;
    uint32_t lastFrame = 0;        // latest frame published
    uint32_t lastAck = 0;          // latest frame a page said it applied
    std::vector<uint32_t> lagAtAck;   // published frame minus acknowledged frame, at each ack
    std::vector<std::vector<std::pair<std::string, double>>> reports;   // "report" messages, in order
};

class Server {
public:
    // Binds and starts serving. Throws Error naming the host and port when the address is invalid or the
    // port is taken.
    explicit Server(const ServerOptions& options);
    ~Server();   // stop()
    Server(const Server&) = delete;
    Server& operator=(const Server&) = delete;

    std::string url() const;       // http://HOST:PORT/
    uint16_t port() const;         // the bound port (the chosen one for port 0)

    void setMesh(const Mesh& mesh, const FrameInfo& info = {});
    void setStream(std::vector<MeshDelta> frames);
    // Live: one frame's delta with its camera and counts. Copies what it needs and posts it to the I/O
    // thread; returns at once.
    void publish(const MeshDelta& delta, const FrameInfo& info);

    ServerStats stats() const;
    // Calls `onReport` on the I/O thread for each "report" a page sends (measurement scripts).
    void onReport(std::function<void(const std::vector<std::pair<std::string, double>>&)> callback);
    void stop();                   // closes every connection and joins the I/O thread; idempotent

    struct Impl;   // the I/O thread's state (viewer_server.cpp); public only so that its session classes can name it

private:
    std::shared_ptr<Impl> impl_;
};

// Blocks until SIGINT or SIGTERM (Ctrl-C) or `seconds` have passed (< 0: no limit); returns true on a signal.
// The signals are blocked in the calling thread first, so call it before creating threads that must not get them
// (blockStopSignals() does only that part).
void blockStopSignals();
bool waitForStopSignal(double seconds);
// Non-blocking: whether SIGINT or SIGTERM is pending (after blockStopSignals()); consumes it.
bool stopSignalPending();

}  // namespace vkmesh::viewer
