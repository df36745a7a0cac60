# Recipes for everyday work; the README's commands are plain cargo and need none of this.

# The whole test suite (what CI runs, plus formatting and lints).
test:
    cargo test --workspace

# Criterion benchmarks; medians end up under target/criterion.
bench:
    cargo bench --workspace
    python3 scripts/criterion-medians.py

# Formatting and lints, as CI checks them.
lint:
    cargo fmt --all -- --check
    cargo clippy --workspace --all-targets -- -D warnings

# Solve the paper's example.
run-example:
    cargo run --release -- solve fixtures/paper-example.json
