#include <cstdio>

int main() {
    std::puts("coarsegrain");
    return 0;
}
