// The status words every kernel reports through: loop caps hit, rays traced, paths truncated.
// Mirrors: src/render.rs (DispatchStatus, describe_status_flags).
// Reads the `status` and `pass_info` bindings (wgsl/bindings.wgsl).

fn flag_status(bit: u32) {
    atomicOr(&status[STATUS_FLAGS], bit);
}

// lavapipe ends all loops of an invocation once 65535 iterations have run in total; a loop
// with a run-time trip count then stops after one iteration (see layout::STATUS_LOOP_LIMIT).
// Called last by every kernel.
fn check_loop_limit() {
    var iterations = 0u;
    for (var i = 0u; i < pass_info.loop_check; i += 1u) {
        iterations += 1u;
    }
    if (iterations != pass_info.loop_check) {
        flag_status(STATUS_LOOP_LIMIT);
    }
}
