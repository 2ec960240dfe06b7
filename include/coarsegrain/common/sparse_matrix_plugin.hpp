// Move semantics for Eigen::SparseMatrix, included inside the class by Eigen
// (EIGEN_SPARSEMATRIX_PLUGIN, set by the coarsegrain CMake target for everything that links it).
// Eigen 3.4 declares a copy constructor and copy assignment but no move ones, so every
// std::move of a SparseMatrix, every return of one from a branch and every assignment of a
// returned one copies all its entries: a transient second copy of the largest matrices (the
// hierarchy's B^k, the fine operator), which set the peak memory of a build. Both leave `other`
// empty (0 x 0) and free what *this held.
// No include guard: Eigen includes it once, inside the class body.

/// Takes other's storage; other is left empty.
SparseMatrix(SparseMatrix&& other) noexcept : SparseMatrix() { swap(other); }

/// Takes other's storage and frees this matrix's; other is left empty.
SparseMatrix& operator=(SparseMatrix&& other) noexcept {
    SparseMatrix taken;
    taken.swap(other);
    swap(taken);
    return *this;
}
