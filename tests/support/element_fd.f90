!> Finite-difference machinery shared by the element tests: allocating wrappers of an
!> element's evaluate and second, central differences of its modes (Jacobian), a 5-point rule
!> for the second directional derivative, the Hessian of one mode by differences of the
!> analytic gradient, the exact Hessian by polarisation of `second`, and the weight's nodal
!> force as minus the central difference of its potential.
module element_fd
  use core_kinds, only: wp
  use elements_base, only: element_t
  use testing, only: suite_t
  use fd_helpers, only: relerr, flat
  implicit none
  private
  public :: evaluate, modes, jacobian, second, fd_jacobian, fd_second, fd_hessian, &
    polar_hessian, fd_weight_force, expect_derivatives

contains

  subroutine evaluate(el, x, e, de)
    class(element_t), intent(in) :: el
    real(wp), intent(in) :: x(:)
    real(wp), allocatable, intent(out) :: e(:), de(:, :)
    allocate(e(el%n_modes()), de(el%n_modes(), size(x)))
    call el%evaluate(x, e, de)
  end subroutine evaluate

  function modes(el, x) result(e)
    class(element_t), intent(in) :: el
    real(wp), intent(in) :: x(:)
    real(wp), allocatable :: e(:)
    real(wp), allocatable :: de(:, :)
    call evaluate(el, x, e, de)
  end function modes

  !> The analytic Jacobian de/dx.
  function jacobian(el, x) result(de)
    class(element_t), intent(in) :: el
    real(wp), intent(in) :: x(:)
    real(wp), allocatable :: e(:), de(:, :)
    call evaluate(el, x, e, de)
  end function jacobian

  function second(el, x, v) result(d2)
    class(element_t), intent(in) :: el
    real(wp), intent(in) :: x(:), v(:)
    real(wp), allocatable :: d2(:)
    allocate(d2(el%n_modes()))
    call el%second(x, v, d2)
  end function second

  !> Central differences of e: column k = de/dx_k.
  function fd_jacobian(el, x, h) result(j)
    class(element_t), intent(in) :: el
    real(wp), intent(in) :: x(:), h
    real(wp), allocatable :: j(:, :)
    real(wp) :: xp(size(x))
    integer :: k
    allocate(j(el%n_modes(), size(x)))
    do k = 1, size(x)
      xp = x
      xp(k) = x(k) + h
      j(:, k) = modes(el, xp)
      xp(k) = x(k) - h
      j(:, k) = (j(:, k) - modes(el, xp)) / (2 * h)
    end do
  end function fd_jacobian

  !> 5-point FD of d2/ds2 e(x + s v) at s = 0 (error O(s^4)).
  function fd_second(el, x, v, s) result(d2)
    class(element_t), intent(in) :: el
    real(wp), intent(in) :: x(:), v(:), s
    real(wp), allocatable :: d2(:)
    d2 = (-modes(el, x + 2 * s * v) + 16 * modes(el, x + s * v) - 30 * modes(el, x) &
          + 16 * modes(el, x - s * v) - modes(el, x - 2 * s * v)) / (12 * s**2)
  end function fd_second

  !> Hessian of mode m by central differences of the analytic gradient de(m, :).
  function fd_hessian(el, x, m, h) result(hm)
    class(element_t), intent(in) :: el
    real(wp), intent(in) :: x(:), h
    integer, intent(in) :: m
    real(wp) :: hm(size(x), size(x)), xp(size(x))
    real(wp), allocatable :: e(:), dep(:, :), dem(:, :)
    integer :: k
    do k = 1, size(x)
      xp = x
      xp(k) = x(k) + h
      call evaluate(el, xp, e, dep)
      xp(k) = x(k) - h
      call evaluate(el, xp, e, dem)
      hm(:, k) = (dep(m, :) - dem(m, :)) / (2 * h)
    end do
  end function fd_hessian

  !> Hessian of mode m by polarisation of the second directional derivative (exact):
  !> H_ij = [D2(e_i + e_j) - D2(e_i - e_j)] / 4.
  function polar_hessian(el, x, m) result(hm)
    class(element_t), intent(in) :: el
    real(wp), intent(in) :: x(:)
    integer, intent(in) :: m
    real(wp) :: hm(size(x), size(x)), u(size(x)), w(size(x))
    real(wp), allocatable :: a(:), b(:)
    integer :: i, j
    do j = 1, size(x)
      do i = 1, size(x)
        u = 0.0_wp; w = 0.0_wp
        u(i) = u(i) + 1; u(j) = u(j) + 1
        w(i) = w(i) + 1; w(j) = w(j) - 1
        a = second(el, x, u)
        b = second(el, x, w)
        hm(i, j) = (a(m) - b(m)) / 4
      end do
    end do
  end function polar_hessian

  !> -dV/dx of the element's weight potential under gravity g, central differences, step h.
  function fd_weight_force(el, x, g, h) result(f)
    class(element_t), intent(in) :: el
    real(wp), intent(in) :: x(:), g(:), h
    real(wp) :: f(size(x)), xp(size(x)), fw(size(x)), potp, potm
    integer :: k
    do k = 1, size(x)
      xp = x
      xp(k) = x(k) + h
      call el%weight(xp, g, fw, potp)
      xp(k) = x(k) - h
      call el%weight(xp, g, fw, potm)
      f(k) = -(potp - potm) / (2 * h)
    end do
  end function fd_weight_force
  !> The three derivative checks of a rotation element at x along v, with steps scaled by zs,
  !> the distance of x to the element's singularity (each test says why): de against central
  !> differences at h = 1e-6 zs (truncation (h / zs)^2 ~ 1e-12, round-off ~ 10 eps |e| / h),
  !> bound 1e-7 relative to max(|de|, 1); second against the 5-point rule at s = 1e-2
  !> (|v| ~ 0.3 zs: truncation ~ 1e-12, round-off ~ 50 eps |e| / s^2 <= 7e-9), bound 1e-7
  !> relative to max(|d2e|, |v|^2); the polarised Hessian of each mode against differences of
  !> de at h = 1e-5 zs (truncation ~ 1e-10, round-off 10 eps |de| / h), bound 1e-7. The
  !> results go to the suite's categories c_de, c_d2 and c_pol.
  subroutine expect_derivatives(ts, el, x, v, zs, what, c_de, c_d2, c_pol)
    type(suite_t), intent(inout) :: ts
    class(element_t), intent(in) :: el
    real(wp), intent(in) :: x(:), v(:), zs
    character(len=*), intent(in) :: what
    integer, intent(in) :: c_de, c_d2, c_pol
    real(wp) :: err
    integer :: m
    call ts%expect(what // ' de', relerr(flat(jacobian(el, x)), &
      flat(fd_jacobian(el, x, 1.0e-6_wp * zs)), 1.0_wp), 1.0e-7_wp, c_de)
    call ts%expect(what // ' second vs FD d2/ds2', relerr(second(el, x, v), &
      fd_second(el, x, v, 1.0e-2_wp), dot_product(v, v)), 1.0e-7_wp, c_d2)
    err = 0.0_wp
    do m = 1, el%n_modes()
      err = max(err, relerr(flat(polar_hessian(el, x, m)), flat(fd_hessian(el, x, m, &
        1.0e-5_wp * zs)), 1.0_wp))
    end do
    call ts%expect(what // ' Hessian (polarised second) vs FD, all modes', err, 1.0e-7_wp, &
      c_pol)
  end subroutine expect_derivatives
end module element_fd
