!> The spatial beam the element tests share: a general reference orientation (chord along
!> dir from a point off the origin, section y from orient) and distinct stiffnesses and
!> inertias in every direction, so that no check passes by symmetry.
module beam3d_fixture
  use core_kinds, only: wp
  use core_error, only: error_t
  use testing, only: suite_t
  use elements_base, only: MODE_RIGID, MODE_DYNAMIC
  use elements_beam3d, only: beam3d_t, beam3d_set_geometry
  use elements_rotation, only: rotvec_to_euler, euler_to_matrix, euler_product
  implicit none
  private
  public :: make_beam3d, beam3d_state, space_frame

contains

  !> The beam; the suite records that its geometry was accepted.
  function make_beam3d(form, l0, dir, orient, suite) result(b)
    integer, intent(in) :: form
    real(wp), intent(in) :: l0, dir(3), orient(3)
    type(suite_t), intent(inout) :: suite
    type(beam3d_t) :: b
    type(error_t) :: err
    integer :: k
    b%label = 'beam3d'
    b%dofs = [(k, k=1, 14)]
    b%mode_class = [MODE_RIGID, (MODE_DYNAMIC, k=1, 5)]
    call beam3d_set_geometry(b, [0.3_wp, -0.2_wp, 0.5_wp], [0.3_wp, -0.2_wp, 0.5_wp] &
      + l0 * dir / norm2(dir), orient, err)
    call suite%check(err%ok(), 'beam3d_set_geometry accepts a general orientation')
    b%ea = 3.0e4_wp; b%gj = 41.0_wp; b%ei_y = 55.0_wp; b%ei_z = 23.0_wp
    b%rho_a = 2.7_wp; b%rho_j = 0.031_wp; b%rho_iy = 0.017_wp; b%rho_iz = 0.012_wp
    b%bending = form
  end function make_beam3d

  !> Coordinates of a state: chord from xp of length l along R_rig R(tilt) ex0, nodal
  !> rotations R_rig R(th_k) relative to the reference (R_rig = R(rig), rotation vectors).
  function beam3d_state(b, xp, rig, l, tilt, thp, thq) result(x)
    type(beam3d_t), intent(in) :: b
    real(wp), intent(in) :: xp(3), rig(3), l, tilt(3), thp(3), thq(3)
    real(wp) :: x(14), rr(4), r_rig(3, 3), r_tilt(3, 3)
    rr = rotvec_to_euler(rig)
    r_rig = euler_to_matrix(rr)
    r_tilt = euler_to_matrix(rotvec_to_euler(tilt))
    x(1:3) = xp
    x(8:10) = xp + l * matmul(r_rig, matmul(r_tilt, b%ex0))
    x(4:7) = euler_product(rr, rotvec_to_euler(thp))
    x(11:14) = euler_product(rr, rotvec_to_euler(thq))
  end function beam3d_state

  !> A space-frame matrix (12 x 12, local (u, theta) of both nodes, x along the chord) from
  !> its axial and torsional 2 x 2 blocks and its bending 4 x 4 blocks in the x-y and x-z
  !> planes (the x-z block in (w, theta_y) with the textbook's sign convention).
  pure function space_frame(mx, mtor, mxy, mxz) result(k)
    real(wp), intent(in) :: mx(2, 2), mtor(2, 2), mxy(4, 4), mxz(4, 4)
    real(wp) :: k(12, 12), sg(4)
    integer, parameter :: ixz(4) = [3, 5, 9, 11]
    integer :: i, j
    k = 0.0_wp
    k([1, 7], [1, 7]) = mx
    k([4, 10], [4, 10]) = mtor
    k([2, 6, 8, 12], [2, 6, 8, 12]) = mxy
    sg = [1, -1, 1, -1]
    do j = 1, 4
      do i = 1, 4
        k(ixz(i), ixz(j)) = sg(i) * sg(j) * mxz(i, j)
      end do
    end do
  end function space_frame
end module beam3d_fixture
