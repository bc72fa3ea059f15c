!> The slider element (src/elements/elements_slider.f90) against its definition and central
!> finite differences, as test_elements does for the beam, truss and hinge:
!>   - e = n . (x - x_ref) with n the unit normal of the (normalised) direction, for guides in
!>     several directions and random positions; e = 0 anywhere on the guide;
!>   - de against central FD of e, second (= 0) against a 5-point FD of d2/ds2 e(x + s v);
!>   - de^T S de = k n n^T (a spring across the guide, none along it).
program test_slider
  use core_kinds, only: wp
  use testing, only: suite_t
  use fd_helpers, only: lcg_t, relerr, flat
  use elements_base, only: MODE_DYNAMIC
  use elements_slider, only: slider_t
  implicit none

  type(suite_t) :: ts
  type(lcg_t) :: rng = lcg_t(seed=20261123)
  type(slider_t) :: sl
  real(wp) :: x(2), v(2), e(1), de(1, 2), fd(1, 2), d2(1), d2_fd, s(1, 1), dir(2), n(2), h
  real(wp) :: ep(1), em(1), e2(1), e1(1), e0(1), worst_de, worst_d2
  integer :: c, k
  character(len=48) :: what

  call ts%init('slider')
  sl%label = 'guide'
  sl%dofs = [1, 2]
  sl%mode_class = [MODE_DYNAMIC]
  sl%k = 3.5e4_wp
  worst_de = 0.0_wp
  worst_d2 = 0.0_wp
  do c = 1, 6
    write(what, '(a,i0)') 'slider cfg ', c
    ! Directions of any length and quadrant, guides through any point.
    dir = rng%uniform_vec(2, -5.0_wp, 5.0_wp)
    call sl%set_direction(dir)
    sl%x_ref = rng%uniform_vec(2, -2.0_wp, 2.0_wp)
    n = [-dir(2), dir(1)] / norm2(dir)
    call ts%check(abs(norm2(sl%normal(:, 1)) - 1) <= 4 * epsilon(1.0_wp), trim(what) // &
      ': normal has unit length')
    x = rng%uniform_vec(2, -3.0_wp, 3.0_wp)
    v = rng%uniform_vec(2, -1.0_wp, 1.0_wp)
    call sl%evaluate(x, e, de)
    ! |x - x_ref| < 5 * sqrt(2): round-off of the dot product, a few eps times that.
    call ts%check(abs(e(1) - dot_product(n, x - sl%x_ref)) <= 10 * epsilon(1.0_wp) * 8, &
      trim(what) // ': e = n . (x - x_ref)')
    ! Every point x_ref + t dir is on the guide: e = 0 to round-off (|t dir| <= 3 |dir| < 22).
    call sl%evaluate(sl%x_ref + rng%uniform(-3.0_wp, 3.0_wp) * dir, e0, de)
    call ts%check(abs(e0(1)) <= 10 * epsilon(1.0_wp) * 25, trim(what) // ': e = 0 on the guide')
    ! Central differences of a linear function: round-off only, eps |e| / h with |e| < 10.
    h = 1.0e-6_wp
    do k = 1, 2
      call sl%evaluate(x + h * unit(k), ep, fd)
      call sl%evaluate(x - h * unit(k), em, fd)
      fd(1, k) = (ep(1) - em(1)) / (2 * h)
    end do
    call sl%evaluate(x, e, de)
    worst_de = max(worst_de, relerr(flat(de), flat(fd), 1.0_wp))
    call ts%check(relerr(flat(de), flat(fd), 1.0_wp) <= 5 * epsilon(1.0_wp) * 10 / h, &
      trim(what) // ': de = central FD of e')
    ! 5-point second difference with step 1e-2: round-off eps |e| / s^2 times 16/12, |e| < 20.
    h = 1.0e-2_wp
    call sl%evaluate(x + 2 * h * v, e2, de)
    call sl%evaluate(x + h * v, e1, de)
    call sl%evaluate(x - h * v, em, de)
    call sl%evaluate(x - 2 * h * v, ep, de)
    d2_fd = (-e2(1) + 16 * e1(1) - 30 * e(1) + 16 * em(1) - ep(1)) / (12 * h**2)
    call sl%second(x, v, d2)
    worst_d2 = max(worst_d2, abs(d2_fd))
    call ts%check(d2(1) == 0 .and. abs(d2_fd) <= 10 * epsilon(1.0_wp) * 20 * 64 / 12 / h**2, &
      trim(what) // ': second = 0 = 5-point FD')
    call sl%stiffness(s)
    call sl%evaluate(x, e, de)
    call ts%check(relerr(flat(matmul(transpose(de), matmul(s, de))), &
      sl%k * [n(1) * n(1), n(2) * n(1), n(1) * n(2), n(2) * n(2)], 1.0_wp) <= &
      4 * epsilon(1.0_wp), trim(what) // ': de^T S de = k n n^T')
  end do
  write(*, '(a,es10.2,a,es10.2)') '-- worst: de vs FD', worst_de, ', |FD second|', worst_d2
  call spatial_cases()
  call ts%check(sl%type_name() == 'slider', 'type name')
  call ts%check(.not. sl%has_inertia(), 'a slider has no consistent inertia')
  call ts%finish()

contains

  !> Spatial guides (two modes): the normals are orthonormal and normal to the guide (any
  !> direction, also along a coordinate axis), points on the guide give e = 0, a step along
  !> n_k moves e_k alone, and de holds the normals (the modes are linear: exact to round-off).
  subroutine spatial_cases()
    type(slider_t) :: s3
    real(wp) :: d(3), p(3), e3(2), de3(2, 3), g(2, 2)
    integer :: c3
    character(len=40) :: label
    s3%dofs = [1, 2, 3]
    s3%mode_class = [MODE_DYNAMIC, MODE_DYNAMIC]
    do c3 = 1, 5
      write(label, '(a,i0)') 'spatial slider cfg ', c3
      d = rng%uniform_vec(3, -5.0_wp, 5.0_wp)
      if (c3 == 5) d = [0.0_wp, 0.0_wp, 2.0_wp]
      call s3%set_direction(d)
      s3%x_ref = rng%uniform_vec(3, -2.0_wp, 2.0_wp)
      g = matmul(transpose(s3%normal), s3%normal)
      call ts%check(maxval(abs(g - reshape([1.0_wp, 0.0_wp, 0.0_wp, 1.0_wp], [2, 2]))) <= &
        8 * epsilon(1.0_wp), trim(label) // ': normals orthonormal')
      call ts%check(maxval(abs(matmul(d, s3%normal))) <= 8 * epsilon(1.0_wp) * norm2(d), &
        trim(label) // ': normals normal to the guide')
      call s3%evaluate(s3%x_ref + rng%uniform(-3.0_wp, 3.0_wp) * d, e3, de3)
      call ts%check(maxval(abs(e3)) <= 10 * epsilon(1.0_wp) * 40, trim(label) // &
        ': e = 0 on the guide')
      p = s3%x_ref + 0.7_wp * s3%normal(:, 2) + 0.1_wp * d
      call s3%evaluate(p, e3, de3)
      call ts%check(abs(e3(1)) <= 100 * epsilon(1.0_wp) .and. abs(e3(2) - 0.7_wp) <= &
        100 * epsilon(1.0_wp), trim(label) // ': a step along n_2 moves e_2 alone')
      call ts%check(maxval(abs(de3 - transpose(s3%normal))) == 0, trim(label) // &
        ': de rows are the normals')
    end do
  end subroutine spatial_cases

  pure function unit(k) result(u)
    integer, intent(in) :: k
    real(wp) :: u(2)
    u = 0.0_wp
    u(k) = 1.0_wp
  end function unit
end program test_slider
