// LD_PRELOAD shim for scripts/ci/20-portability.sh: records which compute shaders a process dispatched, so
// the job can check that its test subset runs every shader of shaders_comp/ under GPU-assisted validation.
//
// It sits between the program and the Vulkan loader (vkmesh calls the loader's exported functions) and
// forwards every call unchanged. A shader module is named by the FNV-1a 64-bit hash of its SPIR-V words,
// the same hash the job computes over the build's .spv files. At exit it appends one line per distinct
// shader dispatched (vkCmdDispatch or vkCmdDispatchIndirect with a compute pipeline of that module bound)
// to the file $VKMESH_DISPATCH_LOG: "<16 hex digits> <the process's command line>\n" (the command line names
// the test, --gtest_filter=..., for choosing a subset). Several processes may append at once (O_APPEND, one
// write per line).
//
// Built twice by the job: as the shim (gcc -shared -fPIC -O2 -o dispatch_log.so dispatch_log.c -ldl) and, with
// -DDISPATCH_LOG_HASH_FILES, as a program printing "<hash> <file>" for each SPIR-V file named on its command
// line (the same hash, so that no other tool is needed to match the log against the build's shaders).
#define _GNU_SOURCE
#include <dlfcn.h>
#include <fcntl.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <vulkan/vulkan.h>

// Small fixed tables under one lock: vkmesh creates a few dozen modules and pipelines per process.
enum { kMaxEntries = 4096 };
struct Pair { uint64_t key, value; };
static struct Pair modules[kMaxEntries];    // VkShaderModule -> hash
static struct Pair pipelines[kMaxEntries];  // compute VkPipeline -> hash
static struct Pair bound[kMaxEntries];      // VkCommandBuffer -> hash of the bound compute pipeline
static uint64_t dispatched[kMaxEntries];    // distinct hashes dispatched
static int moduleCount, pipelineCount, boundCount, dispatchedCount, overflowed;
static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;

static void* next(const char* name) {
    void* f = dlsym(RTLD_NEXT, name);
    if (!f) {
        fprintf(stderr, "dispatch_log: %s not found below the shim\n", name);
        abort();
    }
    return f;
}

static uint64_t fnv1a(const void* data, size_t bytes) {
    const unsigned char* p = data;
    uint64_t h = 0xcbf29ce484222325ull;
    for (size_t i = 0; i < bytes; ++i) h = (h ^ p[i]) * 0x100000001b3ull;
    return h;
}

// Sets key -> value in a table (replacing an existing key: handles are reused after destruction).
static void put(struct Pair* table, int* count, uint64_t key, uint64_t value) {
    for (int i = 0; i < *count; ++i)
        if (table[i].key == key) { table[i].value = value; return; }
    if (*count == kMaxEntries) { overflowed = 1; return; }
    table[(*count)++] = (struct Pair){key, value};
}

static int get(const struct Pair* table, int count, uint64_t key, uint64_t* value) {
    for (int i = 0; i < count; ++i)
        if (table[i].key == key) { *value = table[i].value; return 1; }
    return 0;
}

VKAPI_ATTR VkResult VKAPI_CALL vkCreateShaderModule(VkDevice device, const VkShaderModuleCreateInfo* info,
                                                    const VkAllocationCallbacks* allocator, VkShaderModule* module) {
    static PFN_vkCreateShaderModule real;
    if (!real) real = (PFN_vkCreateShaderModule)next("vkCreateShaderModule");
    VkResult r = real(device, info, allocator, module);
    if (r == VK_SUCCESS) {
        pthread_mutex_lock(&lock);
        put(modules, &moduleCount, (uint64_t)*module, fnv1a(info->pCode, info->codeSize));
        pthread_mutex_unlock(&lock);
    }
    return r;
}

VKAPI_ATTR VkResult VKAPI_CALL vkCreateComputePipelines(VkDevice device, VkPipelineCache cache, uint32_t count,
                                                        const VkComputePipelineCreateInfo* infos,
                                                        const VkAllocationCallbacks* allocator, VkPipeline* out) {
    static PFN_vkCreateComputePipelines real;
    if (!real) real = (PFN_vkCreateComputePipelines)next("vkCreateComputePipelines");
    VkResult r = real(device, cache, count, infos, allocator, out);
    if (r == VK_SUCCESS) {
        pthread_mutex_lock(&lock);
        for (uint32_t i = 0; i < count; ++i) {
            uint64_t hash;
            if (get(modules, moduleCount, (uint64_t)infos[i].stage.module, &hash))
                put(pipelines, &pipelineCount, (uint64_t)out[i], hash);
        }
        pthread_mutex_unlock(&lock);
    }
    return r;
}

VKAPI_ATTR void VKAPI_CALL vkCmdBindPipeline(VkCommandBuffer cmd, VkPipelineBindPoint point, VkPipeline pipeline) {
    static PFN_vkCmdBindPipeline real;
    if (!real) real = (PFN_vkCmdBindPipeline)next("vkCmdBindPipeline");
    if (point == VK_PIPELINE_BIND_POINT_COMPUTE) {
        pthread_mutex_lock(&lock);
        uint64_t hash;
        if (get(pipelines, pipelineCount, (uint64_t)pipeline, &hash)) put(bound, &boundCount, (uint64_t)(uintptr_t)cmd, hash);
        pthread_mutex_unlock(&lock);
    }
    real(cmd, point, pipeline);
}

static void recordDispatch(VkCommandBuffer cmd) {
    pthread_mutex_lock(&lock);
    uint64_t hash;
    if (get(bound, boundCount, (uint64_t)(uintptr_t)cmd, &hash)) {
        int seen = 0;
        for (int i = 0; i < dispatchedCount && !seen; ++i) seen = dispatched[i] == hash;
        if (!seen) {
            if (dispatchedCount < kMaxEntries) dispatched[dispatchedCount++] = hash;
            else overflowed = 1;
        }
    }
    pthread_mutex_unlock(&lock);
}

VKAPI_ATTR void VKAPI_CALL vkCmdDispatch(VkCommandBuffer cmd, uint32_t x, uint32_t y, uint32_t z) {
    static PFN_vkCmdDispatch real;
    if (!real) real = (PFN_vkCmdDispatch)next("vkCmdDispatch");
    recordDispatch(cmd);
    real(cmd, x, y, z);
}

VKAPI_ATTR void VKAPI_CALL vkCmdDispatchIndirect(VkCommandBuffer cmd, VkBuffer buffer, VkDeviceSize offset) {
    static PFN_vkCmdDispatchIndirect real;
    if (!real) real = (PFN_vkCmdDispatchIndirect)next("vkCmdDispatchIndirect");
    recordDispatch(cmd);
    real(cmd, buffer, offset);
}

__attribute__((destructor)) static void writeLog(void) {
    const char* path = getenv("VKMESH_DISPATCH_LOG");
    if (!path || !*path || (dispatchedCount == 0 && !overflowed)) return;
    int fd = open(path, O_WRONLY | O_CREAT | O_APPEND, 0644);
    if (fd < 0) return;
    char args[512] = "";
    int cmdline = open("/proc/self/cmdline", O_RDONLY);
    if (cmdline >= 0) {
        ssize_t n = read(cmdline, args, sizeof args - 1);
        close(cmdline);
        for (ssize_t i = 0; i < n; ++i)
            if (args[i] == '\0' || args[i] == '\n') args[i] = ' ';
        args[n > 0 ? n : 0] = '\0';
    }
    char line[600];
    for (int i = 0; i < dispatchedCount; ++i) {
        int n = snprintf(line, sizeof line, "%016llx %s\n", (unsigned long long)dispatched[i], args);
        if (n >= (int)sizeof line) n = (int)sizeof line - 1, line[n - 1] = '\n';
        if (write(fd, line, (size_t)n) != n) break;
    }
    if (overflowed && write(fd, "overflow\n", 9) != 9) { /* the job reports a missing line as uncovered */ }
    close(fd);
}

#ifdef DISPATCH_LOG_HASH_FILES
int main(int argc, char** argv) {
    for (int i = 1; i < argc; ++i) {
        FILE* f = fopen(argv[i], "rb");
        if (!f) { perror(argv[i]); return 1; }
        static unsigned char code[1 << 22];
        size_t n = fread(code, 1, sizeof code, f);
        int tooBig = !feof(f);
        fclose(f);
        if (tooBig) { fprintf(stderr, "%s: larger than %zu bytes\n", argv[i], sizeof code); return 1; }
        printf("%016llx %s\n", (unsigned long long)fnv1a(code, n), argv[i]);
    }
    return 0;
}
#endif
