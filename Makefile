# lanterna — the two commands of the README's quick start, and a few helpers.
#   make demo   render the demo scene to out/ (installs what is missing first)
#   make test   run the test suite on lavapipe (installs what is missing first): the Rust
#               tests, then the Python package's (built into .cache/pyenv, see
#               scripts/python-test)

CARGO ?= cargo
SETUP_STAMP := .cache/setup-done

.PHONY: demo test python-test setup bench lint fmt conformance-references

$(SETUP_STAMP): scripts/setup
	@scripts/setup
	@mkdir -p .cache && touch $(SETUP_STAMP)

setup: $(SETUP_STAMP)

# One minute of RIS on the street scene at 480×270 (lavapipe renders ~0.06 M samples/s on 2 cores).
demo: $(SETUP_STAMP)
	$(CARGO) run --release -- render scenes/street.gltf --width 480 --method ris --time 60 -o out/street.exr --png out/street.png

test: $(SETUP_STAMP)
	$(CARGO) test --release
	$(MAKE) python-test

# The Python tests compare renders with the release CLI, so build it first.
python-test: $(SETUP_STAMP)
	$(CARGO) build --release
	scripts/python-test -q

bench: $(SETUP_STAMP)
	$(CARGO) run --release -- bench

lint:
	$(CARGO) fmt --all -- --check
	scripts/module-cycles
	$(CARGO) clippy --all-targets -- -D warnings
	$(CARGO) clippy --all-targets --features python -- -D warnings

# Re-render the committed Mitsuba references of the conformance suite (needs Mitsuba:
# scripts/setup --mitsuba) after a conformance scene changed.
conformance-references: $(SETUP_STAMP)
	LANTERNA_WRITE_REFERENCES=1 $(CARGO) test --release --test conformance -- --test-threads 1
