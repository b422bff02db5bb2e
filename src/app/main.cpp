#include "candela/util/error.h"

#include <cstdio>

int main(int, char**) {
    std::fprintf(stderr, "candela: under construction\n");
    return 1;
}
