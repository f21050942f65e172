// The page's files, embedded in the binary at build time (cmake/EmbedAssets.cmake generates the table from
// src/viewer/assets/ and Debian's three.js): the server serves these and nothing else.
#pragma once

#include <cstddef>
#include <string_view>

namespace vkmesh::viewer {

struct Asset {
    std::string_view path;          // URL path, "/index.html"
    std::string_view contentType;
    std::string_view body;
};

// The asset at exactly this URL path ("/" is "/index.html"), or nullptr.
const Asset* findAsset(std::string_view path);
// Every asset, for tests and the listing in docs.
const Asset* assetsBegin();
const Asset* assetsEnd();

}  // namespace vkmesh::viewer
