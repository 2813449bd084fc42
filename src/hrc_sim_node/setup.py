from setuptools import find_packages, setup

package_name = 'hrc_sim_node'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test', 'bench']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/params', ['../../params/sim.yaml']),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='hrc developers',
    maintainer_email='hrc@example.org',
    description='Slider-pendulum-ball physics (PyBullet) and the sim node of hrc.',
    license='Apache-2.0',
    entry_points={'console_scripts': [
        'sim_node = hrc_sim_node.sim_node:main',
    ]},
)
