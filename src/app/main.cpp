#include <iostream>
int main() { std::cout << "planetsculpt\n"; }
