!> The truss in space (elements_truss with dim = 3) at element level:
!>   - e = |x_q - x_p| - l0 against the closed form on random states, e = 0 undeformed;
!>   - de against central FD, second against a 5-point FD, the Hessian by polarisation of
!>     second against FD of de;
!>   - invariance of e under rigid motions (random large rotations and translations);
!>   - linear limit: de^T S de = EA/l0 d d^T blocks, P Hess(e) = P/l (I - d d^T) blocks;
!>   - consistent mass rho A l0 / 6 [2 1; 1 2] per direction, lumped rho A l0 / 2, weight the
!>     total weight half and half with its potential (f = -dV/dx);
!>   - the planar truss (dim = 2) and the spatial one agree on states in the plane z = 0.
!> Achieved errors are printed with every check and the worst per category at the end.
program test_truss3d
  use core_kinds, only: wp
  use testing, only: suite_t
  use fd_helpers, only: lcg_t, relerr, flat, random_rotvec
  use element_fd, only: modes, jacobian, second, fd_jacobian, fd_second, fd_hessian, &
    polar_hessian, fd_weight_force
  use elements_base, only: MODE_DYNAMIC
  use elements_rotation, only: rotvec_to_euler, euler_to_matrix
  use elements_truss, only: truss_t
  implicit none

  real(wp), parameter :: PI = 3.14159265358979323846_wp
  integer, parameter :: C_E = 1, C_DE = 2, C_D2 = 3, C_POL = 4, C_INV = 5, C_K = 6, C_M = 7, &
    C_2D = 8, N_CAT = 8
  character(len=44), parameter :: CAT_NAME(N_CAT) = [character(len=44) :: &
    'e vs closed form', 'de vs central FD of e', 'second vs 5-point FD d2/ds2 e(x+sv)', &
    'Hessian by polarisation vs FD Hessian', 'rigid-motion invariance of e', &
    'stiffness and geometric stiffness', 'mass, weight', 'planar truss = spatial in z = 0']
  type(lcg_t) :: rng = lcg_t(seed=20260312)
  type(suite_t) :: ts
  type(truss_t) :: tr

  call ts%init('truss3d')
  tr = make_truss(3, 1.3_wp)
  call state_tests()
  call linear_limit()
  call mass_tests()
  call planar_agreement()
  call ts%print_worst(CAT_NAME)
  call ts%finish()

contains

  function make_truss(dim, l0) result(t)
    integer, intent(in) :: dim
    real(wp), intent(in) :: l0
    type(truss_t) :: t
    integer :: k
    t%label = 'truss'
    t%dim = dim
    allocate(t%dofs, source=[(k, k=1, 2 * dim)])
    allocate(t%mode_class, source=[MODE_DYNAMIC])
    t%l0 = l0
    t%ea = 2.5e4_wp
    t%rho_a = 1.7_wp
  end function make_truss

  !> A unit vector of random direction.
  function random_dir() result(d)
    real(wp) :: d(3)
    d = rng%uniform_vec(3, -1.0_wp, 1.0_wp)
    d = d / norm2(d)
  end function random_dir

  subroutine state_tests()
    real(wp) :: x(6), v(6), y(6), d(3), l, r(3, 3), c(3), e(1), err
    character(len=40) :: what
    integer :: k
    do k = 1, 8
      write(what, '(a,i0)') 'truss3d state ', k
      d = random_dir()
      l = tr%l0 * rng%uniform(0.8_wp, 1.2_wp)
      x(1:3) = rng%uniform_vec(3, -2.0_wp, 2.0_wp)
      x(4:6) = x(1:3) + l * d
      e = modes(tr, x)
      ! Differences of coordinates up to ~3.6 and a square root: a few eps of 3.6; bound 1e-14.
      call ts%expect(trim(what) // ' e = l - l0', abs(e(1) - (l - tr%l0)), 1.0e-14_wp, C_E)
      ! Central differences at 1e-5: round-off ~ 5 eps * 3.6 / 1e-5 = 4e-10, truncation
      ! h^2 |e'''| / 6 with |e'''| ~ 3 / l^2 < 5: 1e-10; bound 5e-9 (10x).
      call ts%expect(trim(what) // ' de', relerr(flat(jacobian(tr, x)), &
        flat(fd_jacobian(tr, x, 1.0e-5_wp)), 1.0_wp), 5.0e-9_wp, C_DE)
      ! 5-point rule at s = 1e-2 along |v| < 0.35 per component (|dv| / l < 0.6): truncation
      ! s^4 |d6e| / 90 ~ 1e-8 * 720 * 0.6^6 / 90 ~ 4e-9 |v|^2, round-off 5 * 5 eps * 3.6 /
      ! s^2 ~ 2e-10; bound 5e-8 relative to max(|d2e|, |v|^2).
      v = rng%uniform_vec(6, -0.2_wp, 0.2_wp)
      call ts%expect(trim(what) // ' second vs FD d2/ds2', relerr(second(tr, x, v), &
        fd_second(tr, x, v, 1.0e-2_wp), dot_product(v, v)), 5.0e-8_wp, C_D2)
      ! FD of de (entries <= 1) at 1e-5: truncation h^2 |e''''| / 6 ~ 1e-10 * 24 / l^3 / 6 <
      ! 1e-9, round-off eps / h ~ 2e-11 per entry of size 1 / l; bound 1e-8.
      err = relerr(flat(polar_hessian(tr, x, 1)), flat(fd_hessian(tr, x, 1, 1.0e-5_wp)), &
        1.0_wp)
      call ts%expect(trim(what) // ' Hessian (polarised second) vs FD', err, 1.0e-8_wp, C_POL)
      r = euler_to_matrix(rotvec_to_euler(random_rotvec(rng, PI)))
      c = rng%uniform_vec(3, -3.0_wp, 3.0_wp)
      y(1:3) = matmul(r, x(1:3)) + c
      y(4:6) = matmul(r, x(4:6)) + c
      ! Coordinates up to ~7 after the move: a few eps of 7; bound 1e-13 (~60 eps).
      call ts%expect(trim(what) // ' e invariant under rigid motion', &
        maxval(abs(modes(tr, y) - e)), 1.0e-13_wp, C_INV)
    end do
  end subroutine state_tests

  !> Outer-product blocks [[a, -a], [-a, a]] of a 3 x 3 matrix a.
  pure function bar_blocks(a) result(k)
    real(wp), intent(in) :: a(3, 3)
    real(wp) :: k(6, 6)
    k(1:3, 1:3) = a
    k(4:6, 4:6) = a
    k(1:3, 4:6) = -a
    k(4:6, 1:3) = -a
  end function bar_blocks

  subroutine linear_limit()
    real(wp), parameter :: pforce = -870.0_wp
    real(wp) :: x(6), d(3), dd(3, 3), id(3, 3), de(1, 6), s(1, 1), k(6, 6), e(1)
    integer :: i
    d = random_dir()
    x(1:3) = [0.2_wp, -0.1_wp, 0.4_wp]
    x(4:6) = x(1:3) + tr%l0 * d
    e = modes(tr, x)
    call ts%expect('truss3d e = 0 undeformed', abs(e(1)), 1.0e-14_wp, C_E)
    de = jacobian(tr, x)
    call tr%stiffness(s)
    k = matmul(transpose(de), matmul(s, de))
    dd = spread(d, 2, 3) * spread(d, 1, 3)
    ! Products of direction cosines and one division: a few eps of EA/l0; bound 1e-13.
    call ts%expect('truss3d de^T S de = EA/l0 [d d^T blocks]', relerr(flat(k), &
      flat(tr%ea / tr%l0 * bar_blocks(dd)), 1.0_wp), 1.0e-13_wp, C_K)
    id = 0.0_wp
    do i = 1, 3
      id(i, i) = 1.0_wp
    end do
    call ts%expect('truss3d P Hess(e) = P/l0 [(I - d d^T) blocks]', relerr(flat(pforce * &
      polar_hessian(tr, x, 1)), flat(pforce / tr%l0 * bar_blocks(id - dd)), 1.0_wp), &
      1.0e-13_wp, C_K)
  end subroutine linear_limit

  subroutine mass_tests()
    real(wp), parameter :: g(3) = [0.3_wp, -9.81_wp, 1.7_wp]
    real(wp) :: x(6), m(6, 6), h(6), want(6, 6), f(6), pot, diag(6)
    integer :: i
    type(truss_t) :: lumped
    x(1:3) = rng%uniform_vec(3, -2.0_wp, 2.0_wp)
    x(4:6) = x(1:3) + 1.1_wp * tr%l0 * random_dir()
    call tr%inertia(x, rng%uniform_vec(6, -1.0_wp, 1.0_wp), m, h)
    want = 0.0_wp
    do i = 1, 3
      want([i, i + 3], [i, i + 3]) = tr%rho_a * tr%l0 / 6 * reshape([2, 1, 1, 2], [2, 2])
    end do
    ! Two roundings per entry on either side: <= 4 eps; bound 1e-14 (~45 eps).
    call ts%expect('truss3d M = rho A l0 / 6 [2 1; 1 2] per direction', relerr(flat(m), &
      flat(want), 1.0_wp), 1.0e-14_wp, C_M)
    call ts%check(tr%has_inertia() .and. all(h == 0), 'truss3d: consistent, constant (h = 0)')
    call tr%weight(x, g, f, pot)
    call ts%expect('truss3d weight: half the total weight on each node', relerr(f, &
      tr%rho_a * tr%l0 / 2 * [g, g], 1.0_wp), 1.0e-14_wp, C_M)
    call ts%expect('truss3d weight: nodal forces sum to rho A l0 g', relerr(f(1:3) + f(4:6), &
      tr%rho_a * tr%l0 * g, 1.0_wp), 1.0e-14_wp, C_M)
    ! V is linear in x: central differences exact up to round-off ~ eps |V| / h ~ 1e-10 (|V|
    ! ~ 50, h = 1e-4); bound 1e-9 relative to |f| ~ 10.
    call ts%expect('truss3d weight f = -dV/dx (FD)', relerr(f, &
      fd_weight_force(tr, x, g, 1.0e-4_wp), 1.0_wp), 1.0e-9_wp, C_M)
    lumped = tr
    lumped%consistent = .false.
    call lumped%lumped_mass(diag)
    call ts%expect('truss3d lumped: rho A l0 / 2 per translation', relerr(diag, &
      tr%rho_a * tr%l0 / 2 * [1, 1, 1, 1, 1, 1] * 1.0_wp, 1.0_wp), 1.0e-15_wp, C_M)
    call lumped%inertia(x, x, m, h)
    call lumped%weight(x, g, f, pot)
    call ts%check(.not. lumped%has_inertia() .and. all(m == 0) .and. all(f == 0) .and. &
      pot == 0, 'truss3d lumped: inertia and weight left to the lumped masses')
    call tr%lumped_mass(diag)
    call ts%check(all(diag == 0), 'truss3d consistent: no lumped diagonal')
    call ts%check(tr%n_modes() == 1 .and. tr%type_name() == 'truss', &
      'truss3d: one mode, type name truss')
  end subroutine mass_tests

  !> In the plane z = 0 the spatial truss is the planar one: same e, de, second, mass, weight.
  subroutine planar_agreement()
    type(truss_t) :: t2
    real(wp), parameter :: g(3) = [0.3_wp, -9.81_wp, 0.0_wp]
    real(wp) :: x2(4), x3(6), v2(4), v3(6), de3(1, 6), m2(4, 4), m3(6, 6), h2(4), h3(6)
    real(wp) :: f2(4), f3(6), p2, p3, err
    integer, parameter :: I3(4) = [1, 2, 4, 5]
    integer :: k
    t2 = make_truss(2, tr%l0)
    call ts%check(t2%dim == 2 .and. tr%dim == 3 .and. dim_default() == 2, &
      'truss dim defaults to 2')
    err = 0.0_wp
    do k = 1, 5
      x2 = rng%uniform_vec(4, -2.0_wp, 2.0_wp)
      v2 = rng%uniform_vec(4, -0.2_wp, 0.2_wp)
      x3 = [x2(1:2), 0.0_wp, x2(3:4), 0.0_wp]
      v3 = [v2(1:2), 0.0_wp, v2(3:4), 0.0_wp]
      de3 = jacobian(tr, x3)
      err = max(err, maxval(abs(modes(tr, x3) - modes(t2, x2))), &
        maxval(abs(de3(:, I3) - jacobian(t2, x2))), maxval(abs(de3(:, [3, 6]))), &
        maxval(abs(second(tr, x3, v3) - second(t2, x2, v2))))
      call tr%inertia(x3, x3, m3, h3)
      call t2%inertia(x2, x2, m2, h2)
      call tr%weight(x3, g, f3, p3)
      call t2%weight(x2, g, f2, p2)
      err = max(err, maxval(abs(m3(I3, I3) - m2)), maxval(abs(f3(I3) - f2)), abs(p3 - p2))
    end do
    ! The same operations on the same numbers (a zero z adds exactly 0): bound 1e-14.
    call ts%expect('truss dim 3 in z = 0 = truss dim 2', err, 1.0e-14_wp, C_2D)
  end subroutine planar_agreement

  integer function dim_default()
    type(truss_t) :: t
    dim_default = t%dim
  end function dim_default
end program test_truss3d
