// One Vulkan context per test program, with the Khronos validation layer on: every test fails if the
// layer reported anything while it ran.
#pragma once

#include <gtest/gtest.h>

#include <memory>

#include "vk/context.h"

namespace vkmesh::test {

class GpuTest : public ::testing::Test {
protected:
    static vk::Context& context() {
        static std::unique_ptr<vk::Context> ctx = std::make_unique<vk::Context>(vk::ContextOptions{-1, true});
        return *ctx;
    }
    void SetUp() override { context().takeValidationMessages(); }
    void TearDown() override {
        auto messages = context().takeValidationMessages();
        EXPECT_TRUE(messages.empty()) << messages.size() << " validation messages, first: " << messages.front();
    }
};

}  // namespace vkmesh::test
