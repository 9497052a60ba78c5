// An explicit graph of ops over tensors (ggml style): shapes are inferred as nodes are added, a lifetime-based
// planner places every intermediate tensor in one device arena, concat is free (its inputs are placed side by
// side inside it), in-place ops alias their input, and the executor enqueues everything on the one in-order queue.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "graph/planner.hpp"
#include "ops/elementwise.hpp"
#include "ops/view.hpp"
#include "runtime/context.hpp"

namespace ngi::detail {

using TensorId = int;

// What a node does. Ops own their parameters (weights live on the device from construction on).
class Op {
public:
    virtual ~Op() = default;
    virtual std::string kind() const = 0;
    virtual Shape infer(const std::vector<Shape>& in) const = 0;  // throws InputError on a mismatch
    virtual std::size_t scratch_floats(const std::vector<Shape>&) const { return 0; }
    virtual bool in_place() const { return false; }  // the output aliases input 0
    virtual double flops(const std::vector<Shape>&) const { return 0; }
    virtual void enqueue(Context& ctx, const std::vector<View>& in, const View& out, cl_mem scratch,
                         std::vector<cl_event>* events) = 0;
};

struct NodeProfile {
    std::string name, kind;
    double ms = 0;      // sum of its kernels' device time
    double gflop = 0;   // useful work (convolutions); 0 for memory-bound ops
    int launches = 0;   // kernels (and device copies) it enqueued
};

struct RunStats {
    int sanitized_inputs = 0;          // NaN/Inf values replaced in the input
    std::vector<NodeProfile> nodes;    // filled when the device queue has profiling enabled
};

class Graph {
public:
    TensorId input(const Shape& shape, const std::string& name);
    TensorId add(std::shared_ptr<Op> op, const std::vector<TensorId>& inputs, const std::string& name);
    // Channel concatenation without a copy: the inputs are placed one after the other inside the result.
    TensorId concat(const std::vector<TensorId>& inputs, const std::string& name);
    // Whether t can become a member of a new concat: not the graph input (or an in-place alias of it) and not
    // already inside a concat. Otherwise copy it first (CopyNode).
    bool placeable(TensorId t) const;
    void set_output(TensorId t) { output_ = t; }
    // What +-Inf in the input becomes (NaN always becomes 0); default: the float range.
    void set_input_limits(float lo, float hi) { input_lo_ = lo; input_hi_ = hi; }

    const Shape& shape(TensorId t) const { return tensors_.at(t).shape; }
    const Shape& output_shape() const { return tensors_.at(output_).shape; }
    std::size_t node_count() const { return nodes_.size(); }

    // Plans memory and allocates the arena and the scratch buffer. Call once after the last add().
    void compile(Context& ctx);
    std::size_t arena_bytes() const { return plan_.arena_size * sizeof(float); }
    std::size_t naive_bytes() const { return plan_.naive_size * sizeof(float); }
    std::size_t scratch_bytes() const { return scratch_floats_ * sizeof(float); }

    // input: shape(input) floats; output: shape(output) floats.
    RunStats run(Context& ctx, const float* input, float* output);
    // Device in, device out, nothing waited for: the input is copied on the device from `in` at byte `in_offset`
    // into the arena, the output from the arena to `out` at `out_offset`. No host transfer: the count of
    // sanitized input values stays on the device until sanitized_count() reads it.
    void enqueue(Context& ctx, cl_mem in, std::size_t in_offset, cl_mem out, std::size_t out_offset);
    int sanitized_count(Context& ctx);
    std::size_t input_bytes() const { return tensors_.at(input_).shape.size() * sizeof(float); }
    std::size_t output_bytes() const { return tensors_.at(output_).shape.size() * sizeof(float); }

private:
    struct Tensor {
        Tensor(const Shape& s, std::string n, int p = -1) : shape(s), name(std::move(n)), producer(p) {}
        Shape shape;
        std::string name;
        int producer = -1;           // node index; -1 for the input and concats
        int parent = -1;             // tensor this one lives inside (concat member or in-place alias)
        std::size_t offset = 0;      // floats, inside parent
        std::vector<int> consumers;  // node indices
        bool is_concat = false;
    };
    struct Node {
        std::shared_ptr<Op> op;
        std::vector<TensorId> inputs;
        TensorId output;
        std::string name;
    };
    TensorId root(TensorId t) const;
    // Sanitizes the input in the arena and enqueues every node; events per node when profiling.
    void enqueue_nodes(Context& ctx, std::vector<std::vector<cl_event>>* events);
    View view(TensorId t) const;

    std::vector<Tensor> tensors_;
    std::vector<Node> nodes_;
    TensorId input_ = -1, output_ = -1;
    float input_lo_ = -3.402823466e38f, input_hi_ = 3.402823466e38f;
    ArenaPlan plan_;
    std::vector<std::size_t> root_offset_;  // per tensor: offset of its root in the arena (floats)
    std::size_t scratch_floats_ = 0;
    Buffer arena_, scratch_;
    std::unique_ptr<Elementwise> elementwise_;
    bool compiled_ = false;
};

}  // namespace ngi::detail
