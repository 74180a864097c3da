// stokesian command-line entry point (CLI implemented in engine/cli.cpp).
int main() { return 0; }
