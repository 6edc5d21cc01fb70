"""A zoo of foreign PlatformCtrl targets for the suite, the fuzzer and the benchmarks (issue 17). Members are
started with the toolkit's one launcher, pltf.harness.launch. See zoo/README.md."""
