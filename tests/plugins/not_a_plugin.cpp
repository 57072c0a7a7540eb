// A shared library without pneumo's entry point (tests/plugin_test.cpp).
extern "C" __attribute__((visibility("default"))) int not_a_plugin_answer() { return 42; }
