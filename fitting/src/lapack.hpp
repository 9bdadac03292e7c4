#pragma once
// LAPACK's Fortran interface (Debian's liblapack-dev), the routines fitting calls: the singular
// value decomposition and the eigenvalues of a general real matrix. Column-major arrays; the
// character arguments' hidden lengths (the gfortran calling convention) are passed last.
#include <cstddef>

extern "C" {
void dgesvd_(const char* jobu, const char* jobvt, const int* m, const int* n, double* a, const int* lda, double* s,
             double* u, const int* ldu, double* vt, const int* ldvt, double* work, const int* lwork, int* info,
             std::size_t jobu_len, std::size_t jobvt_len);
void dgeev_(const char* jobvl, const char* jobvr, const int* n, double* a, const int* lda, double* wr, double* wi,
            double* vl, const int* ldvl, double* vr, const int* ldvr, double* work, const int* lwork, int* info,
            std::size_t jobvl_len, std::size_t jobvr_len);
}
