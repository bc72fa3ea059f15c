!> Spatial hinge between two rotational nodes p and q. Coordinates x (8) = (lambda_p(4),
!> lambda_q(4)): Euler parameters (scalar first) of each node's rotation relative to the
!> reference orientation, as for elements_beam3d ((1,0,0,0) undeformed).
!>
!> Hinge frame, fixed to node p and given in the reference (global) frame: the axis n and
!> perpendicular unit vectors t1, t2 = n x t1. The relative rotation in p's body axes is the
!> quaternion mu = conj(lambda_p) lambda_q (R(mu) = R_p^T R_q, times |lambda_p|^2 |lambda_q|^2
!> off the unit sphere): bilinear in x. With its hinge-frame components written as the
!> complex numbers z = mu0 + i (mu_v.n) and w = mu_v.t1 + i (mu_v.t2), the three modes are
!>   e1 = 2 atan2(mu_v.n, mu0) = 2 arg z,        e2 + i e3 = 2 w / conj(z) = 2 w z / |z|^2.
!> Their meaning: a relative rotation with bending angle beta < pi splits uniquely (swing-twist)
!> as R_p^T R_q = Rot(m, beta) Rot(n, phi), a twist phi about the axis followed by a bending
!> rotation about m = cos(g) t1 + sin(g) t2 in p's plane normal to the axis. Then
!> z = cos(beta/2) exp(i phi/2), w = sin(beta/2) exp(i (g - phi/2)), so
!>   e1 = phi (exact, |phi| < 2 pi),     (e2, e3) = 2 tan(beta/2) (cos g, sin g),
!> the bending rotation about t1, t2 to first order (2 tan(beta/2) = beta + beta^3/12 + ...).
!>
!> Range and representation: e1 lies in (-2 pi, 2 pi]. Like the angle form of the beam it is
!> scale-free (degree 0 in each lambda), but the sign of a lambda matters: lambda and -lambda are
!> the same orientation and give e1 values 2 pi apart. With Euler parameters that follow
!> continuously from the reference, e1 is the continuous hinge angle up to a full turn either
!> way (mu0 > 0 for |e1| < pi). e2, e3 do not depend on the signs. Everything is singular only at
!> a bending angle of pi (z = 0), where a floor keeps the results finite.
module elements_hinge3d
  use core_kinds, only: wp
  use core_error, only: error_t, ERR_INPUT
  use elements_base, only: element_t
  use elements_rotation, only: euler_product, cross, unit_normal, orthonormal_frame
  implicit none
  private
  public :: hinge3d_t, hinge3d_set_axis

  !> Floor of |z|^2 relative to |mu|^2 = cos^2(beta/2): only reached within ~1e-15 rad of a
  !> bending angle of pi (or at lambda = 0), where the modes are singular anyway.
  real(wp), parameter :: Z2_FLOOR = 1.0e-30_wp

  type, extends(element_t) :: hinge3d_t
    real(wp) :: axis(3) = [0.0_wp, 0.0_wp, 1.0_wp]   !< hinge axis n (unit, reference frame)
    real(wp) :: perp1(3) = [1.0_wp, 0.0_wp, 0.0_wp]  !< t1: unit, perpendicular to the axis
    real(wp) :: perp2(3) = [0.0_wp, 1.0_wp, 0.0_wp]  !< t2 = axis x perp1 (right-handed)
    real(wp) :: k = 0.0_wp          !< torsion stiffness on e1 [N m / rad]
    real(wp) :: k_b(2) = 0.0_wp     !< bending stiffnesses on e2, e3 [N m / rad]
  contains
    procedure :: evaluate => hinge3d_evaluate
    procedure :: second => hinge3d_second
    procedure :: stiffness => hinge3d_stiffness
    procedure, nopass :: type_name => hinge3d_type_name
    procedure :: mode_period => hinge3d_period
  end type hinge3d_t

contains

  !> The hinge frame from its axis; perp1 is orthogonalised from `perp` when given, otherwise
  !> from the coordinate axis least aligned with the axis (the first of equals), so the frame
  !> is a deterministic function of the axis. An error for a zero axis or a `perp` parallel to it.
  subroutine hinge3d_set_axis(h, axis, err, perp)
    class(hinge3d_t), intent(inout) :: h
    real(wp), intent(in) :: axis(3)
    type(error_t), intent(out) :: err
    real(wp), intent(in), optional :: perp(3)
    real(wp) :: n(3), t(3), a, frame(3, 3)
    logical :: ok
    a = norm2(axis)
    if (.not. a > 0) then
      call err%set(ERR_INPUT, 'hinge3d: the hinge axis has zero length')
      return
    end if
    n = axis / a
    t = unit_normal(n)
    if (present(perp)) t = perp
    call orthonormal_frame(n, t, frame, ok)
    if (.not. ok) then
      call err%set(ERR_INPUT, 'hinge3d: the perpendicular vector is zero or (nearly) '// &
        'parallel to the hinge axis')
      return
    end if
    h%axis = frame(:, 1)
    h%perp1 = frame(:, 2)
    h%perp2 = frame(:, 3)
  end subroutine hinge3d_set_axis

  pure function conj(l) result(c)
    real(wp), intent(in) :: l(4)
    real(wp) :: c(4)
    c = [l(1), -l(2:4)]
  end function conj

  !> Rows of the map from mu to its hinge-frame components (mu0, mu_v.n, mu_v.t1, mu_v.t2).
  pure function frame_map(this) result(p)
    class(hinge3d_t), intent(in) :: this
    real(wp) :: p(4, 4)
    p = 0.0_wp
    p(1, 1) = 1.0_wp
    p(2, 2:4) = this%axis
    p(3, 2:4) = this%perp1
    p(4, 2:4) = this%perp2
  end function frame_map

  !> z and w of the module comment, their gradients zg, wg (8) and, along v (when present),
  !> their first and second directional derivatives; 1/conj(z) as u (floored at z = 0).
  pure subroutine components(this, x, z, w, zg, wg, u, v, z1, w1, z2, w2)
    class(hinge3d_t), intent(in) :: this
    real(wp), intent(in) :: x(:)
    complex(wp), intent(out) :: z, w, zg(8), wg(8), u
    real(wp), intent(in), optional :: v(:)
    complex(wp), intent(out), optional :: z1, w1, z2, w2
    real(wp) :: p(4, 4), mu(4), dmu(4, 8), y(4), yg(4, 8), unit(4), d(4)
    integer :: j
    p = frame_map(this)
    mu = euler_product(conj(x(1:4)), x(5:8))
    ! mu is bilinear: its columns are products with unit quaternions.
    do j = 1, 4
      unit = 0.0_wp
      unit(j) = 1.0_wp
      dmu(:, j) = euler_product(conj(unit), x(5:8))
      dmu(:, 4 + j) = euler_product(conj(x(1:4)), unit)
    end do
    y = matmul(p, mu)
    yg = matmul(p, dmu)
    z = cmplx(y(1), y(2), wp)
    w = cmplx(y(3), y(4), wp)
    zg = cmplx(yg(1, :), yg(2, :), wp)
    wg = cmplx(yg(3, :), yg(4, :), wp)
    u = z / max(abs(z)**2, Z2_FLOOR * dot_product(mu, mu), tiny(1.0_wp))
    if (.not. present(v)) return
    d = matmul(p, euler_product(conj(v(1:4)), x(5:8)) + euler_product(conj(x(1:4)), v(5:8)))
    z1 = cmplx(d(1), d(2), wp)
    w1 = cmplx(d(3), d(4), wp)
    d = matmul(p, 2 * euler_product(conj(v(1:4)), v(5:8)))
    z2 = cmplx(d(1), d(2), wp)
    w2 = cmplx(d(3), d(4), wp)
  end subroutine components

  !> e1 = 2 arg z: de1 = 2 Im(dz / z); e2 + i e3 = 2 w u: d = 2 (dw u + w du), du = -conj(dz) u^2.
  pure subroutine hinge3d_evaluate(this, x, e, de)
    class(hinge3d_t), intent(in) :: this
    real(wp), intent(in) :: x(:)
    real(wp), intent(out) :: e(:), de(:, :)
    complex(wp) :: z, w, zg(8), wg(8), u, eb, ebg(8)
    call components(this, x, z, w, zg, wg, u)
    ! atan2(0, 0) is not allowed: a bending angle of exactly pi leaves the twist undefined.
    e(1) = 0.0_wp
    if (z /= (0.0_wp, 0.0_wp)) e(1) = 2 * atan2(aimag(z), real(z))
    de(1, :) = 2 * aimag(zg * conjg(u))
    eb = 2 * w * u
    ebg = 2 * (wg * u - w * u**2 * conjg(zg))
    e(2) = real(eb)
    e(3) = aimag(eb)
    de(2, :) = real(ebg)
    de(3, :) = aimag(ebg)
  end subroutine hinge3d_evaluate

  !> Along v: d2e1 = 2 Im(z'' / z - (z' / z)^2); with u = 1 / conj(z), u'' = -conj(z'') u^2
  !> + 2 conj(z')^2 u^3 and (e2 + i e3)'' = 2 (w'' u + 2 w' u' + w u'').
  pure subroutine hinge3d_second(this, x, v, d2e)
    class(hinge3d_t), intent(in) :: this
    real(wp), intent(in) :: x(:), v(:)
    real(wp), intent(out) :: d2e(:)
    complex(wp) :: z, w, zg(8), wg(8), u, z1, w1, z2, w2, u1, u2, eb2
    call components(this, x, z, w, zg, wg, u, v, z1, w1, z2, w2)
    d2e(1) = 2 * aimag(z2 * conjg(u) - (z1 * conjg(u))**2)
    u1 = -conjg(z1) * u**2
    u2 = -conjg(z2) * u**2 + 2 * conjg(z1)**2 * u**3
    eb2 = 2 * (w2 * u + 2 * w1 * u1 + w * u2)
    d2e(2) = real(eb2)
    d2e(3) = aimag(eb2)
  end subroutine hinge3d_second

  !> diag(k, k_b(1), k_b(2)): the modes are angles (to first order for e2, e3) in radians.
  pure subroutine hinge3d_stiffness(this, s)
    class(hinge3d_t), intent(in) :: this
    real(wp), intent(out) :: s(:, :)
    s = 0.0_wp
    s(1, 1) = this%k
    s(2, 2) = this%k_b(1)
    s(3, 3) = this%k_b(2)
  end subroutine hinge3d_stiffness

  pure function hinge3d_type_name() result(name)
    character(len=:), allocatable :: name
    name = 'hinge3d'
  end function hinge3d_type_name
  !> e1 = 2 arg z is defined modulo 4 pi (lambda and -lambda give e1 values 2 pi apart, and
  !> a full turn takes lambda to -lambda): the kinematics matches a hinge angle beyond a turn
  !> modulo 4 pi, so a shaft can spin on.
  pure real(wp) function hinge3d_period(this, j) result(p)
    class(hinge3d_t), intent(in) :: this
    integer, intent(in) :: j
    p = 0.0_wp
    if (j == 1) p = 16 * atan(1.0_wp)
  end function hinge3d_period
end module elements_hinge3d
