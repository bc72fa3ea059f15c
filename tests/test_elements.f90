!> Planar elements (docs/theory.md section 2) against central finite differences and textbook
!> matrices: the beam in both bending forms (angle, sine), the truss and the hinge.
!>
!> For every element and several deformed, rotated and translated configurations (chord angles
!> beyond 90 degrees, tangent rotations up to 1.1 rad) it checks
!>   - e against the closed-form definitions, de against FD of e;
!>   - second(x, v) against a 5-point FD of d2/ds2 e(x + s v) and against v^T H_fd v
!>     (H_fd: central differences of de), and the Hessian by polarisation of `second`;
!>   - invariance of e under translation, rotation (+ 2 pi on a nodal angle), e = 0 undeformed;
!>   - linear limit de^T S de = textbook Euler-Bernoulli / Timoshenko / truss stiffness
!>     (rotated to global coordinates), sigma1 Hess(e1_bar) = textbook geometric stiffness;
!>   - consistent mass at the undeformed state = textbook, lumped option;
!>   - convective term h(x, xd) against h_i = sum_jk (dM_ij/dx_k - 1/2 dM_jk/dx_i) xd_j xd_k
!>     with FD of M at deformed states (this validates the inertia coupling);
!>   - weight f = -d potential / dx by FD;
!>   - the beam's closed-form mass, convective force and weight against the direct Gauss-point
!>     quadrature of its material points, and e against the closed-form definitions, on random
!>     states with nodal angles many turns away from the chord angle.
!> Achieved relative errors are printed with every check and summarised at the end.
program test_elements
  use core_kinds, only: wp
  use testing, only: suite_t
  use fd_helpers, only: lcg_t, relerr, flat
  use element_fd, only: evaluate, modes, second, fd_jacobian, fd_second, fd_hessian, &
    polar_hessian, fd_weight_force
  use elements_base, only: element_t, MODE_RIGID, MODE_DYNAMIC
  use elements_beam, only: beam_t, BENDING_ANGLE, BENDING_SINE
  use elements_truss, only: truss_t
  use elements_hinge, only: hinge_t
  implicit none

  real(wp), parameter :: PI = 3.14159265358979323846_wp

  ! Categories of achieved errors (worst over all checks), reported at the end.
  integer, parameter :: C_E = 1, C_DE = 2, C_D2FD = 3, C_D2H = 4, C_POL = 5, C_INV = 6, &
    C_K = 7, C_KG = 8, C_M = 9, C_H = 10, C_W = 11, C_OBJ = 12, C_GAUSS = 13, N_CAT = 13
  character(len=44), parameter :: CAT_NAME(N_CAT) = [character(len=44) :: &
    'e vs closed form', 'de vs central FD of e', &
    'second vs 5-point FD d2/ds2 e(x+sv)', 'second vs v^T (FD Hessian) v', &
    'Hessian by polarisation vs FD Hessian', 'rigid-body invariance of e', &
    'de^T S de vs textbook stiffness', 'P Hess(e1_bar) vs textbook Kg', &
    'consistent mass vs textbook', 'h vs Lagrange FD of M', 'weight vs -FD of potential', &
    'frame invariance of M and h', 'beam M, h, weight vs Gauss-point quadrature']
  type(lcg_t) :: rng = lcg_t(seed=20240611)
  type(suite_t) :: ts

  call ts%init('elements')

  call beam_tests(BENDING_ANGLE, 'angle')
  call beam_tests(BENDING_SINE, 'sine')
  call beam_closed_forms(BENDING_ANGLE, 'angle')
  call beam_closed_forms(BENDING_SINE, 'sine')
  call beam_linear_limit()
  call beam_lumped()
  call truss_tests()
  call hinge_tests()

  call ts%print_worst(CAT_NAME)
  call ts%finish()

contains

  ! ------------------------------------------------------------------ utilities

  pure function rot2(a) result(r)
    real(wp), intent(in) :: a
    real(wp) :: r(2, 2)
    r = reshape([cos(a), sin(a), -sin(a), cos(a)], [2, 2])
  end function rot2

  !> Global-to-local transformation of a planar node set: `kinds` lists per coordinate 1 (x,
  !> followed by its y, marked 2) or 3 (rotation); returns T with u_local = T u_global.
  function local_transform(alpha, kinds) result(t)
    real(wp), intent(in) :: alpha
    integer, intent(in) :: kinds(:)
    real(wp) :: t(size(kinds), size(kinds))
    real(wp) :: c, s
    integer :: k
    c = cos(alpha)
    s = sin(alpha)
    t = 0.0_wp
    do k = 1, size(kinds)
      select case (kinds(k))
      case (1)
        t(k, k) = c; t(k, k + 1) = s
        t(k + 1, k) = -s; t(k + 1, k + 1) = c
      case (3)
        t(k, k) = 1.0_wp
      end select
    end do
  end function local_transform

  !> Rigid motion of an element's coordinates: rotate positions by psi about `c`, add psi to
  !> rotations, then translate by `d`. `kinds` as in local_transform.
  function rigid_move(x, kinds, psi, c, d) result(y)
    real(wp), intent(in) :: x(:), psi, c(2), d(2)
    integer, intent(in) :: kinds(:)
    real(wp) :: y(size(x))
    integer :: k
    y = x
    do k = 1, size(x)
      select case (kinds(k))
      case (1)
        y(k:k + 1) = c + matmul(rot2(psi), x(k:k + 1) - c) + d
      case (3)
        y(k) = x(k) + psi
      end select
    end do
  end function rigid_move

  !> FD of the element mass matrix: dm(:, :, k) = dM/dx_k.
  function fd_mass_derivative(el, x, h) result(dm)
    class(element_t), intent(in) :: el
    real(wp), intent(in) :: x(:), h
    real(wp) :: dm(size(x), size(x), size(x))
    real(wp) :: mp(size(x), size(x)), mm(size(x), size(x)), hv(size(x)), xp(size(x))
    integer :: k
    do k = 1, size(x)
      xp = x
      xp(k) = x(k) + h
      call el%inertia(xp, 0 * x, mp, hv)
      xp(k) = x(k) - h
      call el%inertia(xp, 0 * x, mm, hv)
      dm(:, :, k) = (mp - mm) / (2 * h)
    end do
  end function fd_mass_derivative

  !> Generic FD checks of e, de, second and the Hessian at one configuration. err_d2 and
  !> err_vhv: a priori bounds of the absolute errors of the 5-point second difference
  !> (s = 2e-3) and of v^T H_fd v (h = 1e-5), when the element gives them: the checks then
  !> allow 10 times them (relative to |d2| or floor_d2) instead of 1e-7 and 1e-8.
  subroutine check_derivatives(el, x, v, what, floor_d2, err_d2, err_vhv)
    class(element_t), intent(in) :: el
    real(wp), intent(in) :: x(:), v(:), floor_d2
    character(len=*), intent(in) :: what
    real(wp), intent(in), optional :: err_d2, err_vhv
    real(wp), allocatable :: e(:), de(:, :), d2(:), d2fd(:), vhv(:)
    real(wp) :: hm(size(x), size(x)), tol_d2, tol_vhv
    integer :: m
    call evaluate(el, x, e, de)
    call ts%expect(what // ' de', relerr(flat(de), flat(fd_jacobian(el, x, 2.0e-6_wp)), 1.0_wp), &
      1.0e-8_wp, C_DE)
    d2 = second(el, x, v)
    d2fd = fd_second(el, x, v, 2.0e-3_wp)
    tol_d2 = 1.0e-7_wp
    tol_vhv = 1.0e-8_wp
    if (present(err_d2)) tol_d2 = 10 * err_d2 / max(maxval(abs(d2)), floor_d2)
    if (present(err_vhv)) tol_vhv = 10 * err_vhv / max(maxval(abs(d2)), floor_d2)
    call ts%expect(what // ' second vs FD d2/ds2', relerr(d2, d2fd, floor_d2), tol_d2, C_D2FD)
    allocate(vhv(size(e)))
    do m = 1, size(e)
      hm = fd_hessian(el, x, m, 1.0e-5_wp)
      vhv(m) = dot_product(v, matmul(hm, v))
      call ts%expect(what // ' Hessian (polarised second) vs FD, mode ' // achar(48 + m), &
        relerr(flat(polar_hessian(el, x, m)), flat(hm), floor_d2), 1.0e-7_wp, C_POL)
    end do
    call ts%expect(what // ' second vs v^T H_fd v', relerr(d2, vhv, floor_d2), tol_vhv, C_D2H)
  end subroutine check_derivatives

  !> M symmetric, h vs Lagrange form from FD of M, frame invariance, weight vs -dV/dx.
  subroutine check_inertia(el, x, xd, kinds, what)
    class(element_t), intent(in) :: el
    real(wp), intent(in) :: x(:), xd(:)
    integer, intent(in) :: kinds(:)
    character(len=*), intent(in) :: what
    integer :: n, i, j, k
    real(wp) :: m(size(x), size(x)), h(size(x)), hfd(size(x)), dm(size(x), size(x), size(x))
    real(wp) :: m2(size(x), size(x)), h2(size(x)), t(size(x), size(x)), xr(size(x))
    real(wp) :: f(size(x)), pot, g(2)
    real(wp) :: hs, psi
    n = size(x)
    call el%inertia(x, xd, m, h)
    call ts%expect(what // ' M symmetric', relerr(flat(m), flat(transpose(m)), 1.0_wp), &
      1.0e-14_wp, C_M)
    ! The evaluation's single call gives exactly what second and inertia give apart.
    block
      real(wp) :: d2e(el%n_modes()), d2e_one(el%n_modes()), m1(n, n), h1(n)
      call el%second(x, xd, d2e)
      call el%second_inertia(x, xd, d2e_one, m1, h1)
      call ts%check(all(d2e_one == d2e) .and. all(m1 == m) .and. all(h1 == h), &
        what // ' second_inertia = second and inertia')
      ! With the mode values at x given (the planar beam then takes its tangent rotations
      ! from them, no atan2): the same to round-off (angles of order 1: 1e-15 relative).
      block
        real(wp) :: e(el%n_modes()), de(el%n_modes(), n)
        call el%evaluate(x, e, de)
        call el%second_inertia(x, xd, d2e_one, m1, h1, e)
        call ts%expect(what // ' second_inertia with mode values: d2e', &
          relerr(d2e_one, d2e, 1.0_wp), 1.0e-13_wp, C_M)
        call ts%expect(what // ' second_inertia with mode values: M', &
          relerr(flat(m1), flat(m), 1.0_wp), 1.0e-13_wp, C_M)
        call ts%expect(what // ' second_inertia with mode values: h', &
          relerr(h1, h, 1.0_wp), 1.0e-13_wp, C_M)
      end block
    end block
    dm = fd_mass_derivative(el, x, 1.0e-5_wp)
    hfd = 0.0_wp
    do i = 1, n
      do j = 1, n
        do k = 1, n
          hfd(i) = hfd(i) + (dm(i, j, k) - 0.5_wp * dm(j, k, i)) * xd(j) * xd(k)
        end do
      end do
    end do
    hs = maxval(abs(m)) * dot_product(xd, xd)
    ! Central differences at 1e-5: truncation (h^2) and round-off (eps / h) meet at a floor of
    ! ~2e-9 on the most deformed configurations (steps 1e-4 and 1e-6 both do worse): 3e-8.
    call ts%expect(what // ' h vs sum (dM_ij/dx_k - dM_jk/dx_i / 2) xd_j xd_k', &
      relerr(h, hfd, 1.0e-3_wp * hs), 3.0e-8_wp, C_H)
    ! Objectivity: M(R x) = T^T M(x) T and h(R x, R xd) = T^T h(x, xd) for a rigid rotation.
    psi = 2.1_wp
    xr = rigid_move(x, kinds, psi, [0.4_wp, -0.9_wp], [1.5_wp, 0.25_wp])
    t = local_transform(psi, kinds)
    call el%inertia(xr, matmul(transpose(t), xd), m2, h2)
    call ts%expect(what // ' M frame invariant', relerr(flat(m2), &
      flat(matmul(transpose(t), matmul(m, t))), 1.0_wp), 1.0e-12_wp, C_OBJ)
    call ts%expect(what // ' h frame invariant', relerr(h2, matmul(transpose(t), h), &
      1.0e-3_wp * hs), 1.0e-12_wp, C_OBJ)
    ! Weight: f = -dV/dx.
    g = [0.35_wp, -9.81_wp]
    call el%weight(x, g, f, pot)
    call ts%expect(what // ' weight f = -dV/dx', relerr(f, fd_weight_force(el, x, g, &
      1.0e-5_wp), 1.0_wp), 1.0e-8_wp, C_W)
  end subroutine check_inertia

  ! ------------------------------------------------------------------ beam

  function make_beam(form, alpha0, phi0, l0) result(b)
    integer, intent(in) :: form
    real(wp), intent(in) :: alpha0, phi0(2), l0
    type(beam_t) :: b
    integer :: k
    b%label = 'beam'
    b%dofs = [(k, k=1, 6)]
    b%mode_class = [MODE_RIGID, MODE_DYNAMIC, MODE_DYNAMIC]
    b%l0 = l0
    b%alpha0 = alpha0
    b%phi0 = phi0
    b%ea = 3.0e4_wp
    b%ei = 55.0_wp
    b%rho_a = 2.7_wp
    b%bending = form
    b%consistent = .true.
  end function make_beam

  !> Coordinates of a beam with chord from xp at angle beta, length l, and nodal tangents at
  !> angles thp, thq from the chord.
  function beam_config(b, xp, beta, l, thp, thq) result(x)
    type(beam_t), intent(in) :: b
    real(wp), intent(in) :: xp(2), beta, l, thp, thq
    real(wp) :: x(6)
    x(1:2) = xp
    x(4:5) = xp + l * [cos(beta), sin(beta)]
    x(3) = beta + thp - b%alpha0 + b%phi0(1)
    x(6) = beta + thq - b%alpha0 + b%phi0(2)
  end function beam_config

  !> Closed-form e_bar of docs/theory.md section 2.1 for that configuration.
  function beam_expected(b, l, thp, thq) result(e)
    type(beam_t), intent(in) :: b
    real(wp), intent(in) :: l, thp, thq
    real(wp) :: e(3)
    if (b%bending == BENDING_SINE) then
      e(2) = b%l0 * sin(thp)
      e(3) = -b%l0 * sin(thq)
    else
      e(2) = b%l0 * thp
      e(3) = -b%l0 * thq
    end if
    e(1) = l - b%l0 + (2 * e(2)**2 + e(2) * e(3) + 2 * e(3)**2) / (30 * b%l0)
  end function beam_expected

  subroutine beam_tests(form, fname)
    integer, intent(in) :: form
    character(len=*), intent(in) :: fname
    integer, parameter :: N_CFG = 9
    ! Hand-picked configurations (xp, yp, beta, l/l0, theta_p, theta_q), then random ones.
    real(wp), parameter :: cfg(6, 5) = reshape([ &
      0.30_wp, -0.20_wp, 2.30_wp, 1.02_wp, 0.50_wp, -0.30_wp, &      ! chord at 132 deg
      -1.10_wp, 0.70_wp, -2.60_wp, 0.97_wp, -0.45_wp, 0.60_wp, &     ! chord at -149 deg
      0.05_wp, 2.00_wp, 1.65_wp, 1.00_wp, 0.50_wp, -0.50_wp, &       ! pure bending, 94.5 deg
      2.00_wp, -1.00_wp, 0.10_wp, 1.05_wp, 1.10_wp, -0.90_wp, &      ! large tangent rotations
      -0.70_wp, -1.30_wp, 3.00_wp, 0.99_wp, 0.40_wp, 0.40_wp], &     ! S-shape, 172 deg
      [6, 5])
    type(beam_t) :: b
    real(wp) :: c(6), x(6), v(6), xd(6), y(6), e(3), ey(3), ee(3), floor_d2
    real(wp), allocatable :: ev(:), de(:, :)
    character(len=40) :: what
    integer :: k, j
    real(wp), parameter :: psis(4) = [0.7_wp, 2.9_wp, -2.2_wp, 4.0_wp]
    b = make_beam(form, 0.4_wp, [0.1_wp, -0.25_wp], 0.8_wp)
    do k = 1, N_CFG
      if (k <= 5) then
        c = cfg(:, k)
      else
        c = [rng%uniform(-2.0_wp, 2.0_wp), rng%uniform(-2.0_wp, 2.0_wp), rng%uniform(-PI, PI), &
             rng%uniform(0.9_wp, 1.1_wp), rng%uniform(-0.8_wp, 0.8_wp), rng%uniform(-0.8_wp, 0.8_wp)]
      end if
      write(what, '(a,a,a,i0)') 'beam/', fname, ' cfg ', k
      x = beam_config(b, c(1:2), c(3), c(4) * b%l0, c(5), c(6))
      v = rng%uniform_vec(6, -1.0_wp, 1.0_wp)
      xd = rng%uniform_vec(6, -2.0_wp, 2.0_wp)
      call evaluate(b, x, ev, de)
      e = ev
      ee = beam_expected(b, c(4) * b%l0, c(5), c(6))
      call ts%expect(trim(what) // ' e vs closed form', relerr(e, ee, 1.0e-3_wp), 1.0e-13_wp, C_E)
      ! Sign conventions of docs/theory.md 2.1: pure bending gives e2 = e3, an S-shape e2 = -e3.
      if (k == 3) call ts%check(e(2) > 0 .and. abs(e(2) - e(3)) <= 1.0e-15_wp, &
        trim(what) // ' pure bending: e2 = e3 > 0')
      if (k == 5) call ts%check(e(2) > 0 .and. abs(e(2) + e(3)) <= 1.0e-15_wp, &
        trim(what) // ' S-shape: e2 = -e3')
      floor_d2 = 1.0e-2_wp * b%l0 * dot_product(v, v)
      call check_derivatives(b, x, v, trim(what), floor_d2)
      ! Rigid-body invariance: rotations about a point (+ 2 pi on one nodal angle), translation.
      do j = 1, size(psis)
        y = rigid_move(x, [1, 2, 3, 1, 2, 3], psis(j), [0.3_wp, -0.8_wp], [0.0_wp, 0.0_wp])
        if (j == 2) y(3) = y(3) + 2 * PI
        if (j == 3) y(6) = y(6) - 2 * PI
        ey = modes(b, y)
        call ts%expect(trim(what) // ' e invariant under rotation', relerr(ey, e, 1.0e-3_wp), &
          1.0e-12_wp, C_INV)
      end do
      y = rigid_move(x, [1, 2, 3, 1, 2, 3], 0.0_wp, [0.0_wp, 0.0_wp], [3.1_wp, -4.2_wp])
      call ts%expect(trim(what) // ' e invariant under translation', relerr(modes(b, y), e, &
        1.0e-3_wp), 1.0e-12_wp, C_INV)
      call check_inertia(b, x, xd, [1, 2, 3, 1, 2, 3], trim(what))
    end do
    ! e = 0 in the undeformed state, for any rigid placement of it.
    do j = 1, size(psis)
      x = beam_config(b, [0.0_wp, 0.0_wp], b%alpha0, b%l0, 0.0_wp, 0.0_wp)
      x(3:6:3) = b%phi0
      y = rigid_move(x, [1, 2, 3, 1, 2, 3], psis(j), [-0.3_wp, 0.5_wp], [1.0_wp, 2.0_wp])
      call ts%expect('beam/' // fname // ' e = 0 undeformed', relerr(modes(b, y), [0.0_wp, 0.0_wp, &
        0.0_wp], 1.0_wp), 1.0e-14_wp, C_INV)
    end do
  end subroutine beam_tests

  !> Direct 4-point Gauss quadrature over the beam's material points r(xi) = x_p + xi lv
  !> + c perp(lv), c = (H2 e2 - H4 e3) / l0: m = rhoA l0 sum w J^T J, h = rhoA l0 sum w J^T
  !> d2r, f = rhoA l0 sum w J^T g, V = -rhoA l0 sum w g . r, with J = dr/dx formed point by
  !> point. The element evaluates these sums in closed form.
  subroutine beam_gauss_reference(b, x, xd, g, m, h, f, pot)
    type(beam_t), intent(in) :: b
    real(wp), intent(in) :: x(6), xd(6), g(2)
    real(wp), intent(out) :: m(6, 6), h(6), f(6), pot
    real(wp) :: xi(4), w(4), e(3), de(3, 6), d2e(3), lv(2), dlv(2), u(2), jac(2, 6), dc(6)
    real(wp) :: c, d2c, d2r(2), r(2), h2, h4, s, t
    integer :: i, k
    ! Gauss-Legendre nodes and weights on [0, 1] from their closed forms.
    s = sqrt(3.0_wp / 7 - 2.0_wp / 7 * sqrt(6.0_wp / 5))
    t = sqrt(3.0_wp / 7 + 2.0_wp / 7 * sqrt(6.0_wp / 5))
    xi = [(1 - t) / 2, (1 - s) / 2, (1 + s) / 2, (1 + t) / 2]
    w = [18 - sqrt(30.0_wp), 18 + sqrt(30.0_wp), 18 + sqrt(30.0_wp), 18 - sqrt(30.0_wp)] / 72
    call b%evaluate(x, e, de)
    call b%second(x, xd, d2e)
    lv = x(4:5) - x(1:2)
    dlv = xd(4:5) - xd(1:2)
    u = [-lv(2), lv(1)]
    m = 0.0_wp; h = 0.0_wp; f = 0.0_wp; pot = 0.0_wp
    do i = 1, 4
      h2 = xi(i) - 2 * xi(i)**2 + xi(i)**3
      h4 = xi(i)**3 - xi(i)**2
      c = (h2 * e(2) - h4 * e(3)) / b%l0
      dc = (h2 * de(2, :) - h4 * de(3, :)) / b%l0
      d2c = (h2 * d2e(2) - h4 * d2e(3)) / b%l0
      r = x(1:2) + xi(i) * lv + c * u
      jac = 0.0_wp
      jac(:, 1) = [1 - xi(i), -c]
      jac(:, 2) = [c, 1 - xi(i)]
      jac(:, 4) = [xi(i), c]
      jac(:, 5) = [-c, xi(i)]
      do k = 1, 6
        jac(:, k) = jac(:, k) + u * dc(k)
      end do
      d2r = d2c * u + 2 * dot_product(dc, xd) * [-dlv(2), dlv(1)]
      m = m + w(i) * matmul(transpose(jac), jac)
      h = h + w(i) * matmul(transpose(jac), d2r)
      f = f + w(i) * matmul(g, jac)
      pot = pot - w(i) * dot_product(g, r)
    end do
    m = b%rho_a * b%l0 * m
    h = b%rho_a * b%l0 * h
    f = b%rho_a * b%l0 * f
    pot = b%rho_a * b%l0 * pot
  end subroutine beam_gauss_reference

  !> Closed forms of the beam against their definitions on random states: e against
  !> beam_expected with nodal angles up to 20 turns off and tangent rotations close to +-pi
  !> (the wrap into (-pi, pi]), mass, convective force and weight against the Gauss-point
  !> quadrature.
  subroutine beam_closed_forms(form, fname)
    integer, intent(in) :: form
    character(len=*), intent(in) :: fname
    type(beam_t) :: b
    real(wp) :: c(6), x(6), xd(6), g(2), m(6, 6), h(6), f(6), pot, mr(6, 6), hr(6), fr(6)
    real(wp) :: potr, scale, err(5), e(3), de(3, 6)
    integer :: k, turns(2)
    character(len=48) :: what
    err = 0.0_wp
    do k = 1, 200
      b = make_beam(form, rng%uniform(-PI, PI), [rng%uniform(-PI, PI), rng%uniform(-PI, PI)], &
        rng%uniform(0.01_wp, 2.0_wp))
      b%shear_p = 0.4_wp
      c = [rng%uniform(-2.0_wp, 2.0_wp), rng%uniform(-2.0_wp, 2.0_wp), rng%uniform(-PI, PI), &
           rng%uniform(0.9_wp, 1.1_wp), rng%uniform(-3.1_wp, 3.1_wp), rng%uniform(-3.1_wp, 3.1_wp)]
      ! Every other state with bending as small as on a fine mesh.
      if (mod(k, 2) == 0) c(5:6) = 1.0e-3_wp * c(5:6)
      x = beam_config(b, c(1:2), c(3), c(4) * b%l0, c(5), c(6))
      turns = nint([rng%uniform(-20.0_wp, 20.0_wp), rng%uniform(-20.0_wp, 20.0_wp)])
      x(3:6:3) = x(3:6:3) + 2 * PI * turns
      xd = rng%uniform_vec(6, -2.0_wp, 2.0_wp)
      g = [rng%uniform(-1.0_wp, 1.0_wp), -9.81_wp]
      call b%evaluate(x, e, de)
      ! Rounding x(3), x(6) at up to 130 rad costs ~3e-14 rad: compare e with the floor l0.
      err(1) = max(err(1), relerr(e, beam_expected(b, c(4) * b%l0, c(5), c(6)), b%l0))
      call b%inertia(x, xd, m, h)
      call b%weight(x, g, f, pot)
      call beam_gauss_reference(b, x, xd, g, mr, hr, fr, potr)
      scale = b%rho_a * b%l0
      err(2) = max(err(2), relerr(flat(m), flat(mr), scale))
      err(3) = max(err(3), relerr(h, hr, scale * dot_product(xd, xd)))
      err(4) = max(err(4), relerr(f, fr, scale * norm2(g)))
      err(5) = max(err(5), relerr([pot], [potr], scale * norm2(g) * (norm2(x(1:2)) + b%l0)))
    end do
    what = 'beam/' // fname // ' 200 random states:'
    call ts%expect(trim(what) // ' e vs closed form, many turns', err(1), 1.0e-12_wp, C_E)
    call ts%expect(trim(what) // ' M vs Gauss quadrature', err(2), 1.0e-13_wp, C_GAUSS)
    call ts%expect(trim(what) // ' h vs Gauss quadrature', err(3), 1.0e-13_wp, C_GAUSS)
    call ts%expect(trim(what) // ' weight vs Gauss quadrature', err(4), 1.0e-13_wp, C_GAUSS)
    call ts%expect(trim(what) // ' potential vs Gauss quadrature', err(5), 1.0e-13_wp, C_GAUSS)
  end subroutine beam_closed_forms

  !> Textbook Euler-Bernoulli (phi = 0) or Timoshenko local stiffness on (u1,v1,th1,u2,v2,th2).
  function textbook_beam_k(ea, ei, l, p) result(k)
    real(wp), intent(in) :: ea, ei, l, p
    real(wp) :: k(6, 6), kt(4, 4)
    integer, parameter :: tr(4) = [2, 3, 5, 6]
    k = 0.0_wp
    k(1, 1) = ea / l; k(4, 4) = ea / l; k(1, 4) = -ea / l; k(4, 1) = -ea / l
    kt = reshape([12 * l**0, 6 * l, -12 * l**0, 6 * l, &
                  6 * l, (4 + p) * l**2, -6 * l, (2 - p) * l**2, &
                  -12 * l**0, -6 * l, 12 * l**0, -6 * l, &
                  6 * l, (2 - p) * l**2, -6 * l, (4 + p) * l**2], [4, 4])
    k(tr, tr) = ei / (l**3 * (1 + p)) * kt
  end function textbook_beam_k

  !> Textbook consistent geometric stiffness for axial force P (local coordinates).
  function textbook_beam_kg(pa, l) result(k)
    real(wp), intent(in) :: pa, l
    real(wp) :: k(6, 6)
    integer, parameter :: tr(4) = [2, 3, 5, 6]
    k = 0.0_wp
    k(tr, tr) = pa / (30 * l) * reshape([36 * l**0, 3 * l, -36 * l**0, 3 * l, &
                                         3 * l, 4 * l**2, -3 * l, -l**2, &
                                         -36 * l**0, -3 * l, 36 * l**0, -3 * l, &
                                         3 * l, -l**2, -3 * l, 4 * l**2], [4, 4])
  end function textbook_beam_kg

  !> Textbook consistent mass (local coordinates).
  function textbook_beam_m(rho_a, l) result(m)
    real(wp), intent(in) :: rho_a, l
    real(wp) :: m(6, 6)
    integer, parameter :: tr(4) = [2, 3, 5, 6]
    m = 0.0_wp
    m([1, 4], [1, 4]) = rho_a * l / 6 * reshape([2, 1, 1, 2], [2, 2])
    m(tr, tr) = rho_a * l / 420 * reshape([156 * l**0, 22 * l, 54 * l**0, -13 * l, &
                                           22 * l, 4 * l**2, 13 * l, -3 * l**2, &
                                           54 * l**0, 13 * l, 156 * l**0, -22 * l, &
                                           -13 * l, -3 * l**2, -22 * l, 4 * l**2], [4, 4])
  end function textbook_beam_m

  !> Linear limit at the undeformed state: stiffness, geometric stiffness and mass, for a beam
  !> along x and rotated/translated ones, both bending forms, with and without shear.
  subroutine beam_linear_limit()
    real(wp), parameter :: alphas(3) = [0.0_wp, 2.2_wp, -1.9_wp]
    real(wp), parameter :: pforce = -1234.5_wp   ! compressive axial force sigma1
    integer :: ia, form, ishear
    type(beam_t) :: b
    real(wp) :: x(6), t(6, 6), s(3, 3), k(6, 6), kg(6, 6), hfd(6, 6), m(6, 6), h(6), p
    real(wp), allocatable :: e(:), de(:, :)
    character(len=60) :: what
    do form = BENDING_ANGLE, BENDING_SINE
      do ia = 1, size(alphas)
        do ishear = 0, 1
          b = make_beam(form, alphas(ia), [0.3_wp * ia, -0.5_wp], 0.65_wp)
          p = 0.0_wp
          if (ishear == 1) p = 0.37_wp
          b%shear_p = p
          write(what, '(a,i0,a,f5.2,a,f4.2)') 'beam form ', form, ' alpha0 ', alphas(ia), &
            ' shear P ', p
          x = beam_config(b, [0.7_wp, -0.4_wp], b%alpha0, b%l0, 0.0_wp, 0.0_wp)
          call evaluate(b, x, e, de)
          call b%stiffness(s)
          k = matmul(transpose(de), matmul(s, de))
          t = local_transform(b%alpha0, [1, 2, 3, 1, 2, 3])
          call ts%expect(trim(what) // ' de^T S de = textbook K', relerr(flat(k), &
            flat(matmul(transpose(t), matmul(textbook_beam_k(b%ea, b%ei, b%l0, p), t))), &
            1.0_wp), 1.0e-12_wp, C_K)
          if (ishear == 1) cycle
          kg = pforce * polar_hessian(b, x, 1)
          hfd = pforce * fd_hessian(b, x, 1, 1.0e-5_wp)
          call ts%expect(trim(what) // ' P Hess(e1_bar) = textbook Kg', relerr(flat(kg), &
            flat(matmul(transpose(t), matmul(textbook_beam_kg(pforce, b%l0), t))), 1.0_wp), &
            1.0e-12_wp, C_KG)
          call ts%expect(trim(what) // ' P Hess_fd(e1_bar) = textbook Kg', relerr(flat(hfd), &
            flat(matmul(transpose(t), matmul(textbook_beam_kg(pforce, b%l0), t))), 1.0_wp), &
            1.0e-8_wp, C_KG)
          call b%inertia(x, 0 * x, m, h)
          call ts%expect(trim(what) // ' M = textbook consistent mass', relerr(flat(m), &
            flat(matmul(transpose(t), matmul(textbook_beam_m(b%rho_a, b%l0), t))), 1.0_wp), &
            1.0e-12_wp, C_M)
          call ts%check(all(h == 0.0_wp), trim(what) // ' h = 0 at rest')
        end do
      end do
    end do
  end subroutine beam_linear_limit

  subroutine beam_lumped()
    type(beam_t) :: b
    real(wp) :: diag(6), m(6, 6), h(6), f(6), pot, x(6)
    b = make_beam(BENDING_ANGLE, 0.3_wp, [0.0_wp, 0.0_wp], 0.9_wp)
    b%consistent = .false.
    x = beam_config(b, [0.1_wp, 0.2_wp], 1.0_wp, 0.95_wp, 0.2_wp, -0.1_wp)
    call b%lumped_mass(diag)
    call ts%expect('beam lumped: rhoA l0/2 on translations', relerr(diag([1, 2, 4, 5]), &
      b%rho_a * b%l0 / 2 * [1, 1, 1, 1], 1.0_wp), 1.0e-15_wp, C_M)
    ! Rotations: none (translations only) or the rotary inertia of each half about its node,
    ! rhoA l0/2 (l0/2)^2/3 = rhoA l0^3/24; nothing else.
    call ts%check(all(diag([3, 6]) == 0) .or. all(abs(diag([3, 6]) - b%rho_a * b%l0**3 / 24) &
      <= 1.0e-15_wp * b%rho_a * b%l0**3), 'beam lumped: rotations get 0 or rhoA l0^3/24')
    call ts%check(.not. b%has_inertia(), 'beam lumped: no consistent inertia')
    call b%inertia(x, x, m, h)
    call b%weight(x, [0.0_wp, -9.81_wp], f, pot)
    call ts%check(all(m == 0) .and. all(h == 0) .and. all(f == 0) .and. pot == 0, &
      'beam lumped: inertia and weight are left to the lumped masses')
    b%consistent = .true.
    call b%lumped_mass(diag)
    call ts%check(all(diag == 0) .and. b%has_inertia(), 'beam consistent: no lumped diagonal')
  end subroutine beam_lumped

  ! ------------------------------------------------------------------ truss

  function make_truss(l0) result(tr)
    real(wp), intent(in) :: l0
    type(truss_t) :: tr
    tr%label = 'truss'
    allocate(tr%dofs, source=[1, 2, 3, 4])
    allocate(tr%mode_class, source=[MODE_DYNAMIC])
    tr%l0 = l0
    tr%ea = 2.5e4_wp
    tr%rho_a = 1.7_wp
  end function make_truss

  subroutine truss_tests()
    type(truss_t) :: tr
    real(wp) :: x(4), v(4), xd(4), y(4), beta, l, s(1, 1), k(4, 4), kg(4, 4), t(4, 4), m(4, 4)
    real(wp) :: h(4), diag(4), kl(4, 4), ml(4, 4), e0, w2
    real(wp), allocatable :: e(:), de(:, :)
    real(wp), parameter :: pforce = 870.0_wp
    character(len=40) :: what
    integer :: c
    tr = make_truss(1.3_wp)
    do c = 1, 6
      write(what, '(a,i0)') 'truss cfg ', c
      beta = rng%uniform(-PI, PI)
      if (c == 1) beta = 2.5_wp
      l = tr%l0 * rng%uniform(0.8_wp, 1.2_wp)
      x(1:2) = rng%uniform_vec(2, -2.0_wp, 2.0_wp)
      x(3:4) = x(1:2) + l * [cos(beta), sin(beta)]
      v = rng%uniform_vec(4, -1.0_wp, 1.0_wp)
      xd = rng%uniform_vec(4, -2.0_wp, 2.0_wp)
      call evaluate(tr, x, e, de)
      call ts%expect(trim(what) // ' e = l - l0', abs(e(1) - (l - tr%l0)) / tr%l0, 1.0e-14_wp, C_E)
      ! e(t) = |r + t w| - l0 along x + t v (w = v_B - v_A): |d^6 e / dt^6| <= 45 |w|^6 / d^5
      ! and |d^4 e / dt^4| <= 3 |w|^4 / d^3 at distance d (the extremes of sqrt(l^2 + t^2 |w|^2)
      ! at w normal to r). 5-point second difference at s = 2e-3: truncation s^4/90 max|e^(6)|
      ! over the stencil (d >= l - 2 s |w|), rounding 64 x 4 eps (|x| + l) / (12 s^2). v^T H_fd v
      ! (central differences of the exact gradient, h = 1e-5): each entry off by h^2/6 times a
      ! 4th derivative, <= 3 (sqrt 2)^4 / l^3 along any unit direction of x and so for every
      ! mixed one (symmetric forms), plus 4 eps / h of rounding; times |v|_1^2. The fixed
      ! 1e-7 and 1e-8 were within 5.1x (cfg 4, d2/ds2: 2.0e-8) and 6.1x (cfg 3, v^T H v:
      ! 1.6e-9) of the truncation, the same in both builds; a wrong second derivative is off
      ! by O(|w|^2 / l), 1e5 times these bounds or more.
      w2 = norm2(v(3:4) - v(1:2))
      call check_derivatives(tr, x, v, trim(what), 1.0e-2_wp * dot_product(v, v), &
        err_d2=(2.0e-3_wp)**4 / 90 * 45 * w2**6 / (l - 4.0e-3_wp * w2)**5 + &
        64 * 4 * epsilon(1.0_wp) * (maxval(abs(x)) + l) / (12 * (2.0e-3_wp)**2), &
        err_vhv=sum(abs(v))**2 * ((1.0e-5_wp)**2 / 6 * 12 / l**3 + 4 * epsilon(1.0_wp) / 1.0e-5_wp))
      e0 = e(1)
      y = rigid_move(x, [1, 2, 1, 2], 2.6_wp, [0.5_wp, 0.5_wp], [-3.0_wp, 1.0_wp])
      call ts%expect(trim(what) // ' e invariant under rigid motion', &
        maxval(abs(modes(tr, y) - e0)) / tr%l0, 1.0e-14_wp, C_INV)
      call check_inertia(tr, x, xd, [1, 2, 1, 2], trim(what))
    end do
    ! Linear limit along a rotated direction.
    beta = 2.0_wp
    x = [0.2_wp, -0.1_wp, 0.2_wp + tr%l0 * cos(beta), -0.1_wp + tr%l0 * sin(beta)]
    call evaluate(tr, x, e, de)
    ! sqrt of a sum of squares minus l0: a few roundings, bound 20 eps (observed 0.8 eps).
    call ts%expect('truss e = 0 undeformed', abs(e(1)) / tr%l0, 20 * epsilon(1.0_wp), C_INV)
    call tr%stiffness(s)
    k = matmul(transpose(de), matmul(s, de))
    t = local_transform(beta, [1, 2, 1, 2])
    kl = 0.0_wp
    kl([1, 3], [1, 3]) = tr%ea / tr%l0 * reshape([1, -1, -1, 1], [2, 2])
    call ts%expect('truss de^T S de = EA/L axial', relerr(flat(k), &
      flat(matmul(transpose(t), matmul(kl, t))), 1.0_wp), 1.0e-13_wp, C_K)
    kg = pforce * polar_hessian(tr, x, 1)
    kl = 0.0_wp
    kl([2, 4], [2, 4]) = pforce / tr%l0 * reshape([1, -1, -1, 1], [2, 2])
    call ts%expect('truss P Hess(l) = P/L transverse', relerr(flat(kg), &
      flat(matmul(transpose(t), matmul(kl, t))), 1.0_wp), 1.0e-13_wp, C_KG)
    call tr%inertia(x, 0 * x, m, h)
    ml = 0.0_wp
    ml([1, 3], [1, 3]) = tr%rho_a * tr%l0 / 6 * reshape([2, 1, 1, 2], [2, 2])
    ml([2, 4], [2, 4]) = ml([1, 3], [1, 3])
    call ts%expect('truss M = textbook consistent mass', relerr(flat(m), &
      flat(matmul(transpose(t), matmul(ml, t))), 1.0_wp), 1.0e-14_wp, C_M)
    tr%consistent = .false.
    call tr%lumped_mass(diag)
    call ts%expect('truss lumped: rhoA l0/2 per translation', relerr(diag, &
      [1, 1, 1, 1] * tr%rho_a * tr%l0 / 2, 1.0_wp), 1.0e-15_wp, C_M)
    call ts%check(.not. tr%has_inertia(), 'truss lumped: no consistent inertia')
  end subroutine truss_tests

  ! ------------------------------------------------------------------ hinge

  subroutine hinge_tests()
    type(hinge_t) :: hg
    real(wp) :: x(2), v(2), s(1, 1), e0
    real(wp), allocatable :: e(:), de(:, :)
    character(len=40) :: what
    integer :: c
    hg%label = 'hinge'
    hg%dofs = [1, 2]
    hg%mode_class = [MODE_DYNAMIC]
    hg%phi0 = [0.3_wp, -1.2_wp]
    hg%k = 42.0_wp
    do c = 1, 4
      write(what, '(a,i0)') 'hinge cfg ', c
      x = rng%uniform_vec(2, -3.0_wp, 3.0_wp)
      v = rng%uniform_vec(2, -1.0_wp, 1.0_wp)
      call evaluate(hg, x, e, de)
      call ts%expect(trim(what) // ' e = (phi_q - phi_q0) - (phi_p - phi_p0)', &
        abs(e(1) - ((x(2) - hg%phi0(2)) - (x(1) - hg%phi0(1)))), 1.0e-14_wp, C_E)
      ! e is linear: the FD error is round-off only, eps (|e| + |x|) / h, |e| + |x| < 12; x5.
      call ts%expect(trim(what) // ' de', relerr(flat(de), flat(fd_jacobian(hg, x, 1.0e-6_wp)), &
        1.0_wp), 5 * epsilon(1.0_wp) * 12 / 1.0e-6_wp, C_DE)
      ! Linear e: the 5-point second difference at s = 1e-2 is rounding only, 64 eps (|e| + |x|)
      ! / (12 s^2) <= 64 eps / s^2 = 1.4e-10 (|e| + |x| < 12); x10. The old 1e-10 was below
      ! that estimate and within 5.6x of the observed 1.8e-11 (cfg 4, both builds). A
      ! nonzero second derivative of a (wrong) nonlinear e would be O(|v|^2) ~ 0.1 to 1.
      call ts%expect(trim(what) // ' second = 0 = FD', maxval(abs([second(hg, x, v), &
        fd_second(hg, x, v, 1.0e-2_wp)])), 10 * 64 * epsilon(1.0_wp) / (1.0e-2_wp)**2, C_D2FD)
      e0 = e(1)
      call ts%expect(trim(what) // ' e invariant under rigid rotation', &
        maxval(abs(modes(hg, x + 1.7_wp) - e0)), 1.0e-14_wp, C_INV)
    end do
    call ts%expect('hinge e = 0 at phi0', maxval(abs(modes(hg, hg%phi0))), 1.0e-15_wp, C_INV)
    call hg%stiffness(s)
    call evaluate(hg, hg%phi0, e, de)
    call ts%expect('hinge de^T S de = k [[1,-1],[-1,1]]', relerr(flat(matmul(transpose(de), &
      matmul(s, de))), hg%k * [1, -1, -1, 1] * 1.0_wp, 1.0_wp), 1.0e-15_wp, C_K)
    call ts%check(.not. hg%has_inertia(), 'hinge has no consistent inertia')
  end subroutine hinge_tests
end program test_elements
